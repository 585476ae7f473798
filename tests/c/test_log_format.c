/* test_log_format.c — ln_log's deferred formatting (libln/src/log_format.c): a format and
 * its arguments captured by the caller and rendered later give exactly what vsnprintf gives
 * at once, for every conversion, flag, width, precision, `*` and length it takes; what it
 * does not take (%n, %L, positional arguments, too many arguments) is refused. */
#define _GNU_SOURCE 1

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/types.h>

/* Internal (hidden in libln.so): compiled in. */
#include "../../libln/src/log_format.c"

#include "ln_test.h"

/* Captures, renders and compares with vsnprintf; the capture's result. */
static int same(const char* fmt, ...)
{
    char data[512], rendered[512], direct[512];
    ln_log_arg args[LN_LOG_MAX_ARGS];
    va_list ap, copy;
    va_start(ap, fmt);
    va_copy(copy, ap);
    int n = ln_log_capture(data, sizeof data, args, fmt, &copy);
    va_end(copy);
    vsnprintf(direct, sizeof direct, fmt, ap);
    va_end(ap);
    if (n >= 0) {
        ln_log_render(rendered, sizeof rendered, data, args, n);
        LN_CHECK_STREQ(rendered, direct);
    }
    return n;
}

static void test_conversions_render_as_printf(void)
{
    LN_CHECK_EQ(same("plain text, 100%% sure"), 0);
    LN_CHECK_EQ(same("period %d: joint position %.3f rad", 42, 0.1234), 2);
    LN_CHECK_EQ(same("%i %5d %-5d| %+d %05d % d", -7, 12, 12, 3, -42, 9), 6);
    LN_CHECK_EQ(same("%u %x %X %o %#x %08.3x", 4000000000u, 255u, 255u, 8u, 255u, 10u), 6);
    LN_CHECK_EQ(same("%hhd %hhu %hd %hu", 300, 300, 70000, 70000), 4);
    LN_CHECK_EQ(same("%ld %lu %lld %llu", -5L, 5UL, -9000000000LL, 18000000000000000000ULL), 4);
    LN_CHECK_EQ(same("%zu %zd %jd %ju %td", (size_t)7, (ssize_t)-7, (intmax_t)-1, (uintmax_t)1,
                     (ptrdiff_t)-3),
                5);
    LN_CHECK_EQ(
        same("%f %e %g %G %a %10.2f %-8.1e|", 3.14159, 1e-10, 0.0001, 1e20, 1.5, 2.5, -0.25), 7);
    LN_CHECK_EQ(
        same("%c%c %s|%10s|%-6s|%.2s|%s", 'o', 'k', "text", "right", "left", "cut", (char*)NULL),
        7);
    LN_CHECK_EQ(same("%*d|%-*d|%.*f|%*.*s|", 6, 1, 4, 2, 2, 3.14159, 8, 3, "abcdef"), 9);
    LN_CHECK_EQ(same("%p", (void*)0x1234), 1);
}

static void test_what_is_not_taken(void)
{
    int count = 0;
    LN_CHECK_EQ(same("%n", &count), -1);
    LN_CHECK_EQ(same("%Lf", (long double)1.5), -1);
    LN_CHECK_EQ(same("%2$d %1$d", 1, 2), -1);
    LN_CHECK_EQ(same("%ls", L"wide"), -1);
    LN_CHECK_EQ(same("%d %d %d %d %d %d %d %d %d %d %d %d %d %d %d %d %d", 1, 2, 3, 4, 5, 6, 7, 8,
                     9, 10, 11, 12, 13, 14, 15, 16, 17),
                -1);
    LN_CHECK_EQ(same("ends in %"), -1);
}

static int capture(char* data, size_t cap, ln_log_arg* args, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = ln_log_capture(data, cap, args, fmt, &ap);
    va_end(ap);
    return n;
}

static void test_strings_are_copied_and_cut_to_the_slot(void)
{
    char data[32], out[64];
    ln_log_arg args[LN_LOG_MAX_ARGS];
    char name[] = "a long name that does not fit";
    LN_CHECK_EQ(capture(data, sizeof data, args, "name %s!", name), 1);
    name[0] = 'X'; /* the caller's string changes after the call: the line does not */
    ln_log_render(out, sizeof out, data, args, 1);
    LN_CHECK_STREQ(out, "name a long name that does !"); /* 32 - "name %s!" and 2 NULs */
    LN_CHECK_EQ(capture(data, 8, args, "too long a format"), -1);
}

int main(void)
{
    LN_TEST_RUN(test_conversions_render_as_printf);
    LN_TEST_RUN(test_what_is_not_taken);
    LN_TEST_RUN(test_strings_are_copied_and_cut_to_the_slot);
    LN_TEST_EXIT();
}
