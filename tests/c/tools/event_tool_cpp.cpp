// event_tool_cpp.cpp — the C++ (ln.hpp) side of the event tests: a handler and a caller of
// robot/fault_event through ln::client::connect_event and ln::event.
//
//   event_tool_cpp connect EVENT MIN_SEVERITY COUNT
//       connect a handler stating MIN_SEVERITY; print "ready", then per call one JSON line
//       {"event", "severity", "code", "text"}; reply severity + 1, code * 2, text reversed
//       (a call with code -1 throws instead: its error is "negative code"); exit after COUNT.
//   event_tool_cpp call EVENT SEVERITY CODE TEXT
//       call with a filter min_severity <= SEVERITY; print {"delivered": N, "replies":
//       ["TEXT"|null, ...], "codes": ["OK", ...]} and exit 0 (ln::error: exit 1 with its name).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include <ln/ln.hpp>

#include "event_tool_messages.hpp"

using fault = robot::fault_event_t;

static std::string text_of(const fault::call_t& c)
{
    return std::string(c.text_len ? c.text : "", c.text_len);
}

static int handle(ln::client& clnt, const char* event, unsigned min_severity, int count)
{
    int handled = 0;
    fault::connect_t connect{};
    connect.min_severity = min_severity;
    auto handler =
        clnt.connect_event<fault>(event, connect, [&](ln::event_handler<fault>::call& c) {
            handled++;
            std::string text = text_of(c.data);
            std::printf("{\"event\": \"%s\", \"severity\": %u, \"code\": %d, \"text\": \"%s\"}\n",
                        c.event_name().c_str(), c.data.severity, c.data.code, text.c_str());
            std::fflush(stdout);
            if (c.data.code == -1)
                throw std::runtime_error("negative code");
            std::string reversed(text.rbegin(), text.rend());
            fault::call_t r{};
            r.severity = c.data.severity + 1;
            r.code = c.data.code * 2;
            r.text_len = static_cast<std::uint32_t>(reversed.size());
            r.text = reversed.data();
            c.reply(r);
        });
    std::printf("ready\n");
    std::fflush(stdout);
    while (handled < count)
        clnt.wait_and_handle_service_group_requests("", 1.0);
    return 0;
}

static int call(ln::client& clnt, const char* event, unsigned severity, int code, const char* text)
{
    auto ev = clnt.get_event<fault>(event);
    ev.set_filter([severity](const fault::connect_t& c) { return c.min_severity <= severity; });
    fault::call_t data{};
    data.severity = severity;
    data.code = code;
    std::string t = text;
    data.text_len = static_cast<std::uint32_t>(t.size());
    data.text = t.data();
    int delivered = ev.call(data, 30.0);
    std::printf("{\"delivered\": %d, \"replies\": [", delivered);
    auto results = ev.results();
    for (std::size_t i = 0; i < results.size(); i++) {
        const auto& r = results[i];
        if (r.reply != nullptr)
            std::printf("%s\"%s\"", i ? ", " : "", text_of(*r.reply).c_str());
        else
            std::printf("%snull", i ? ", " : "");
    }
    std::printf("], \"codes\": [");
    for (std::size_t i = 0; i < results.size(); i++)
        std::printf("%s\"%s\"", i ? ", " : "", ln_error_name(results[i].code));
    std::printf("]}\n");
    return 0;
}

int main(int argc, char** argv)
{
    try {
        ln::client clnt("event_tool_cpp");
        if (argc == 5 && !std::strcmp(argv[1], "connect"))
            return handle(clnt, argv[2], static_cast<unsigned>(std::atoi(argv[3])),
                          std::atoi(argv[4]));
        if (argc == 6 && !std::strcmp(argv[1], "call"))
            return call(clnt, argv[2], static_cast<unsigned>(std::atoi(argv[3])),
                        std::atoi(argv[4]), argv[5]);
        std::fprintf(stderr, "usage: see the top of event_tool_cpp.cpp\n");
        return 2;
    } catch (const ln::error& e) {
        std::printf("{\"error\": \"%s\"}\n", e.name());
        std::fprintf(stderr, "event_tool_cpp: %s\n", e.what());
        return 1;
    }
}
