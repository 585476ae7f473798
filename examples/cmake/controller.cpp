// controller.cpp — a small controller built with CMake against an installed links_and_nodes
// (find_package(links_and_nodes), CMakeLists.txt beside it): publishes COUNT samples of
// robot/joint_state on PREFIX.state at 100 Hz (cycle k: position[j] = k * (j + 1) / 1000,
// velocity[j] = -position[j]), then waits up to 10 s for one sample on PREFIX.reference
// (robot/joint_state) and prints its cycle and positions.  Exit status 0 once a reference
// arrived; 1 on an error or when none did.
// Manager from -ln_manager or $LN_MANAGER.  Usage: controller [PREFIX [COUNT]]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include <ln/ln.hpp>

#include "controller_messages.hpp"

int main(int argc, char** argv)
{
    const std::string prefix = argc > 1 ? argv[1] : "controller";
    const int count = argc > 2 ? std::atoi(argv[2]) : 100;
    try {
        ln::client clnt("cmake_controller", argc, argv);
        auto state = clnt.publish<robot::joint_state_t>(prefix + ".state");
        auto reference = clnt.subscribe<robot::joint_state_t>(prefix + ".reference");
        std::printf("controller: libln %s, publishing %d samples on %s.state\n", ln_version(),
                    count, prefix.c_str());
        std::fflush(stdout);
        robot::joint_state_t js{};
        for (int cycle = 1; cycle <= count; cycle++) {
            js.timestamp = cycle * 0.01;
            js.cycle = static_cast<uint32_t>(cycle);
            for (int j = 0; j < 7; j++) {
                js.position[j] = cycle * (j + 1) / 1000.0;
                js.velocity[j] = -js.position[j];
            }
            state.write(js, 0.1);
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        robot::joint_state_t ref{};
        if (!reference.read(ref, 10.0)) {
            std::fprintf(stderr, "controller: no sample on %s.reference within 10 s\n",
                         prefix.c_str());
            return 1;
        }
        std::printf("controller: reference cycle %u position", static_cast<unsigned>(ref.cycle));
        for (double p : ref.position)
            std::printf(" %g", p);
        std::printf("\n");
        return 0;
    } catch (const ln::error& e) {
        std::fprintf(stderr, "controller: %s\n", e.what());
        return 1;
    }
}
