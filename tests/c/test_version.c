/* test_version.c — the version macros, ln_version() and the compatibility rule of
 * ln_version_check(): same major, library minor >= caller minor. */
#include <stdio.h>

#include <ln/ln.h>

#include "ln_test.h"

static void test_string_matches_numbers(void)
{
    char expected[32];
    snprintf(expected, sizeof expected, "%d.%d.%d", LN_VERSION_MAJOR, LN_VERSION_MINOR,
             LN_VERSION_PATCH);
    LN_CHECK_STREQ(LN_VERSION_STRING, expected);
    LN_CHECK_STREQ(ln_version(), LN_VERSION_STRING);
    LN_CHECK_STREQ(LN_VERSION_STRING, "0.1.0");
    LN_CHECK_EQ(LN_SOVERSION, 1);
}

static void test_compatible(void)
{
    LN_CHECK_EQ(LN_VERSION_CHECK(), LN_OK);
    LN_CHECK_EQ(ln_version_check(LN_VERSION_MAJOR, LN_VERSION_MINOR), LN_OK);
    LN_CHECK_EQ(ln_version_check(LN_VERSION_MAJOR, 0), LN_OK);
}

static void test_incompatible(void)
{
    LN_CHECK_EQ(ln_version_check(LN_VERSION_MAJOR, LN_VERSION_MINOR + 1), LN_EVERSION);
    LN_CHECK_EQ(ln_version_check(LN_VERSION_MAJOR + 1, 0), LN_EVERSION);
    LN_CHECK_EQ(ln_version_check(LN_VERSION_MAJOR + 1, LN_VERSION_MINOR), LN_EVERSION);
}

static void test_invalid(void)
{
    LN_CHECK_EQ(ln_version_check(-1, 0), LN_EINVAL);
    LN_CHECK_EQ(ln_version_check(LN_VERSION_MAJOR, -1), LN_EINVAL);
}

int main(void)
{
    LN_TEST_RUN(test_string_matches_numbers);
    LN_TEST_RUN(test_compatible);
    LN_TEST_RUN(test_incompatible);
    LN_TEST_RUN(test_invalid);
    LN_TEST_EXIT();
}
