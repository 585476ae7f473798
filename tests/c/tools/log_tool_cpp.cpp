// log_tool_cpp.cpp — logs through the C++ API (client.log()), for the Python client logging
// tests: one line per level, printing "line LEVEL N" for each; then flushes.
//   log_tool_cpp NAME        The manager: $LN_MANAGER.
#include <iostream>
#include <string>

#include <ln/ln.hpp>

int main(int argc, char** argv)
{
    if (argc != 2) {
        std::cerr << "usage: log_tool_cpp NAME\n";
        return 2;
    }
    try {
        ln::client clnt(argv[1]);
        for (int level :
             {LN_LOG_DEBUG, LN_LOG_INFO, LN_LOG_WARNING, LN_LOG_ERROR, LN_LOG_CRITICAL}) {
            int line = __LINE__ + 1;
            if (!clnt.log(level, "c++ line at level " + std::to_string(level)))
                throw std::runtime_error("dropped");
            std::cout << "line " << level << " " << line << std::endl;
        }
        ln::check(ln_log_flush(clnt.get(), 10.0));
        std::cout << "flushed" << std::endl;
    } catch (const std::exception& e) {
        std::cout << "error: " << e.what() << std::endl;
        return 1;
    }
    return 0;
}
