// topic_tool_cpp.cpp — the C++ side of the cross-language topic tests, through ln.hpp:
//   topic_tool_cpp pub-joint TOPIC COUNT    same values as topic_tool.c's pub-joint
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <ln/ln.hpp>

#include "topic_messages.hpp"

int main(int argc, char** argv)
{
    if (argc != 4 || std::strcmp(argv[1], "pub-joint") != 0) {
        std::fprintf(stderr, "usage: topic_tool_cpp pub-joint TOPIC COUNT\n");
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
