// daemon_test.hpp — what the ln_daemon unit tests add to tests/c/ln_test.h: a string
// comparison that copies both sides, since LN_CHECK_STREQ would keep a pointer into a
// temporary std::string, and passed(), which takes an Outcome apart for the checks.
#ifndef LN_DAEMON_TEST_HPP
#define LN_DAEMON_TEST_HPP

#include <cstdio>
#include <string>

#include "ln_test.h"
#include "outcome.hpp"

#define CHECK_STR(a, b)                                                                            \
    do {                                                                                           \
        std::string ln_a_ = (a), ln_b_ = (b);                                                      \
        if (ln_a_ != ln_b_) {                                                                      \
            ln_test_fail(__FILE__, __LINE__, #a " == " #b);                                        \
            std::fprintf(stderr, "    \"%s\" != \"%s\"\n", ln_a_.c_str(), ln_b_.c_str());          \
        }                                                                                          \
    } while (0)

// Whether `o` went through (a reply, or an answer that follows later); a refusal's text goes
// to `text` and its code to `code`, for the checks of the wording that follow.
inline bool passed(const lnd::Outcome &o, std::string &text)
{
    text = o.text;
    return !o.failed();
}
inline bool passed(const lnd::Outcome &o, lnd::proto::Err &code, std::string &text)
{
    code = o.code;
    return passed(o, text);
}

#endif // LN_DAEMON_TEST_HPP
