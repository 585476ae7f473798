/* ln_test.h — the few assertion macros the C and C++ tests need, no framework.
 * A failed check prints file:line and both values and the test goes on; LN_TEST_RUN prints
 * one ok/FAIL line per test function and LN_TEST_EXIT makes main return 1 on any failure. */
#ifndef LN_TEST_H
#define LN_TEST_H

#include <stdio.h>
#include <string.h>

static int ln_test_failures;

static inline void ln_test_fail(const char* file, int line, const char* what)
{
    fprintf(stderr, "%s:%d: check failed: %s\n", file, line, what);
    ln_test_failures++;
}

#define LN_CHECK(cond)                                                                             \
    do {                                                                                           \
        if (!(cond))                                                                               \
            ln_test_fail(__FILE__, __LINE__, #cond);                                               \
    } while (0)

/* Integers of any width and signedness, printed as long long. */
#define LN_CHECK_EQ(a, b)                                                                          \
    do {                                                                                           \
        long long ln_a_ = (long long)(a), ln_b_ = (long long)(b);                                  \
        if (ln_a_ != ln_b_) {                                                                      \
            ln_test_fail(__FILE__, __LINE__, #a " == " #b);                                        \
            fprintf(stderr, "    %lld != %lld\n", ln_a_, ln_b_);                                   \
        }                                                                                          \
    } while (0)

/* Strings; NULL compares equal only to NULL. */
#define LN_CHECK_STREQ(a, b)                                                                       \
    do {                                                                                           \
        const char *ln_a_ = (a), *ln_b_ = (b);                                                     \
        if (ln_a_ == NULL || ln_b_ == NULL ? ln_a_ != ln_b_ : strcmp(ln_a_, ln_b_) != 0) {         \
            ln_test_fail(__FILE__, __LINE__, #a " == " #b);                                        \
            fprintf(stderr, "    \"%s\" != \"%s\"\n", ln_a_ ? ln_a_ : "(null)",                    \
                    ln_b_ ? ln_b_ : "(null)");                                                     \
        }                                                                                          \
    } while (0)

static inline void ln_test_run(const char* name, void (*test)(void))
{
    int before = ln_test_failures;
    test();
    printf("%s %s\n", ln_test_failures == before ? "ok  " : "FAIL", name);
    fflush(stdout);
}

#define LN_TEST_RUN(test) ln_test_run(#test, test)
#define LN_TEST_EXIT() return ln_test_failures ? 1 : 0

#endif /* LN_TEST_H */
