// clock_tool_cpp.cpp — clock_tool.c through the C++ API (client.use_clock(), client.now()),
// for the Python recording tests; same arguments and lines.  The manager: $LN_MANAGER.
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

#include <ln/ln.hpp>

int main(int argc, char** argv)
{
    if (argc != 2) {
        std::cerr << "usage: clock_tool_cpp TOPIC|-\n";
        return 2;
    }
    try {
        ln::client clnt("clock_tool_cpp");
        clnt.use_clock(std::strcmp(argv[1], "-") == 0 ? "" : argv[1]);
        std::cout << "ready" << std::endl;
        std::string line;
        while (std::getline(std::cin, line)) {
            if (line.compare(0, 3, "now") != 0)
                continue;
            long n = std::strtol(line.c_str() + 3, nullptr, 10);
            for (long i = 0; i < (n < 1 ? 1 : n); i++)
                std::cout << (i ? " " : "") << clnt.now();
            std::cout << std::endl;
        }
    } catch (const std::exception& e) {
        std::cout << "error: " << e.what() << std::endl;
        return 1;
    }
    return 0;
}
