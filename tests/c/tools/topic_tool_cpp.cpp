// topic_tool_cpp.cpp — the C++ side of the cross-language topic tests, through ln.hpp:
//   topic_tool_cpp pub-joint TOPIC COUNT           same values as topic_tool.c's pub-joint
//   topic_tool_cpp sub-joint TOPIC COUNT TIMEOUT [udp|tcp]
//                                                  queued; prints like topic_tool.c's sub-joint,
//                                                  odd samples by copy, even ones borrowed;
//                                                  udp/tcp: the transport flag it subscribes with
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <ln/ln.hpp>

#include "topic_messages.hpp"

static void print_joint(const robot::joint_state_t& js)
{
    std::printf("%u %.17g", static_cast<unsigned>(js.cycle), js.timestamp);
    for (int j = 0; j < 7; j++)
        std::printf(" %.17g %.17g %.17g", js.position[j], js.velocity[j], js.effort[j]);
    std::printf("\n");
}

static int sub_joint(const char* topic, unsigned long long count, double timeout, unsigned flags)
{
    ln::client clnt("topic_tool_cpp");
    auto sub = clnt.subscribe<robot::joint_state_t>(topic, 1024, flags);
    std::printf("ready\n");
    std::fflush(stdout);
    for (unsigned long long n = 1; n <= count; n++) {
        if (n % 2) {
            robot::joint_state_t js;
            if (!sub.read(js, timeout))
                return std::fprintf(stderr, "topic_tool_cpp: no sample %llu\n", n), 3;
            print_joint(js);
        } else {
            auto view = sub.borrow(timeout);
            if (!view)
                return std::fprintf(stderr, "topic_tool_cpp: no sample %llu\n", n), 3;
            robot::joint_state_t js = *view;
            if (!view.release())
                return std::fprintf(stderr, "topic_tool_cpp: sample %llu overwritten\n", n), 3;
            print_joint(js);
        }
    }
    std::printf("overruns %llu publishers %d\n", static_cast<unsigned long long>(sub.overruns()),
                sub.publisher_count());
    return 0;
}

int main(int argc, char** argv)
{
    if ((argc == 5 || argc == 6) && std::strcmp(argv[1], "sub-joint") == 0) {
        unsigned flags = 0;
        if (argc == 6)
            flags = std::strcmp(argv[5], "tcp") == 0 ? LN_SUBSCRIBE_TCP : LN_SUBSCRIBE_UDP;
        try {
            return sub_joint(argv[2], std::strtoull(argv[3], nullptr, 10), std::atof(argv[4]),
                             flags);
        } catch (const ln::error& e) {
            std::fprintf(stderr, "topic_tool_cpp: %s (%d)\n", e.what(), e.code());
            return 2;
        }
    }
    if (argc != 4 || std::strcmp(argv[1], "pub-joint") != 0) {
        std::fprintf(stderr, "usage: see the top of topic_tool_cpp.cpp\n");
        return 2;
    }
    try {
        ln::client clnt("topic_tool_cpp");
        auto pub = clnt.publish<robot::joint_state_t>(argv[2]);
        std::printf("ready\n");
        std::fflush(stdout);
        unsigned long long count = std::strtoull(argv[3], nullptr, 10);
        for (unsigned long long i = 1; i <= count; i++) {
            auto slot = pub.borrow_slot();
            robot::joint_state_t& js = *slot;
            std::memset(&js, 0, sizeof js);
            js.timestamp = static_cast<double>(i) * 0.001;
            js.cycle = static_cast<std::uint32_t>(i);
            for (int j = 0; j < 7; j++) {
                js.position[j] = static_cast<double>(i) + j / 8.0;
                js.velocity[j] = -static_cast<double>(i) - j / 4.0;
                js.effort[j] = static_cast<double>(i * j);
            }
            slot.commit();
        }
    } catch (const ln::error& e) {
        std::fprintf(stderr, "topic_tool_cpp: %s (%d)\n", e.what(), e.code());
        return 2;
    }
    return 0;
}
