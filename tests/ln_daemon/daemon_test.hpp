// daemon_test.hpp — what the ln_daemon unit tests add to tests/c/ln_test.h: a string
// comparison that copies both sides, since LN_CHECK_STREQ would keep a pointer into a
// temporary std::string.
#ifndef LN_DAEMON_TEST_HPP
#define LN_DAEMON_TEST_HPP

#include <cstdio>
#include <string>

#include "ln_test.h"

#define CHECK_STR(a, b)                                                                       \
    do {                                                                                      \
        std::string ln_a_ = (a), ln_b_ = (b);                                                 \
        if (ln_a_ != ln_b_) {                                                                 \
            ln_test_fail(__FILE__, __LINE__, #a " == " #b);                                   \
            std::fprintf(stderr, "    \"%s\" != \"%s\"\n", ln_a_.c_str(), ln_b_.c_str());     \
        }                                                                                     \
    } while (0)

#endif // LN_DAEMON_TEST_HPP
