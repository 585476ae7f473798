// service_echo_cpp.cpp — the lntest/echo service through ln.hpp, for the Python service tests:
// a C++ provider and caller that must interoperate with the C ones.  Manager from $LN_MANAGER.
//   service_echo_cpp provide NAME [pool]   serve until stdin closes ("ready" once registered);
//                                           "fail" -> exception, "reply" -> explicit respond()
//   service_echo_cpp once NAME TEXT        one call; prints {"rc":"OK"|"E...","text":S}
#include <sys/select.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include <ln/ln.hpp>

#include "service_messages.hpp"

using echo = lntest::echo_t;
using call_t = ln::service_provider<echo>::call;

static int provide(ln::client& clnt, const std::string& name, bool pool)
{
    auto prov = clnt.provide_service<echo>(
        name,
        [](call_t& c) {
            std::string text(c.req.text, c.req.text_len);
            if (text == "fail")
                throw std::runtime_error("C++ echo refuses \"fail\"");
            c.resp.caller = c.req.caller;
            c.resp.seq = c.req.seq;
            // The request's text lives until the handler returns: echo it as is.
            c.resp.text_len = c.req.text_len;
            c.resp.text = c.req.text;
            if (text == "reply")
                c.respond();
        },
        "cpp");
    if (pool) {
        clnt.set_max_threads("cpp_pool", 2);
        clnt.handle_service_group_in_thread_pool("cpp", "cpp_pool");
    }
    std::printf("ready\n");
    std::fflush(stdout);
    if (pool) {
        std::string line;
        while (std::getline(std::cin, line)) {
        }
        return 0;
    }
    for (;;) {
        clnt.wait_and_handle_service_group_requests("cpp", 0.05);
        fd_set fds;
        FD_ZERO(&fds);
        FD_SET(0, &fds);
        timeval zero{0, 0};
        if (select(1, &fds, nullptr, nullptr, &zero) > 0) {
            char buf[64];
            if (read(0, buf, sizeof buf) <= 0)
                return 0;
        }
    }
}

static int once(ln::client& clnt, const std::string& name, std::string text)
{
    auto svc = clnt.get_service<echo>(name);
    svc.req.caller = 3;
    svc.req.seq = 4;
    svc.req.text_len = static_cast<std::uint32_t>(text.size());
    svc.req.text = text.data();
    try {
        svc.call(10.0);
    } catch (const ln::error& e) {
        std::printf("{\"rc\":\"%s\",\"text\":\"\"}\n", e.name());
        return 0;
    }
    std::string got(svc.resp.text, svc.resp.text_len);
    bool same = svc.resp.caller == 3 && svc.resp.seq == 4;
    std::printf("{\"rc\":\"%s\",\"text\":\"%s\"}\n", same ? "OK" : "MISMATCH", got.c_str());
    return 0;
}

int main(int argc, char** argv)
{
    if (argc < 3) {
        std::fprintf(stderr, "usage: see the comment at the top of service_echo_cpp.cpp\n");
        return 2;
    }
    try {
        ln::client clnt("service_echo_cpp");
        std::string mode = argv[1];
        if (mode == "provide")
            return provide(clnt, argv[2], argc > 3 && std::strcmp(argv[3], "pool") == 0);
        if (mode == "once" && argc > 3)
            return once(clnt, argv[2], argv[3]);
    } catch (const ln::error& e) {
        std::fprintf(stderr, "service_echo_cpp: %s\n", e.what());
        return 2;
    }
    return 2;
}
