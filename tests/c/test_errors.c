/* test_errors.c — the error table in ln.h and the library's view of it agree: every entry has
 * a unique name, a unique negative code in one contiguous run, and its own message;
 * codes outside the table are handled. */
#include <limits.h>

#include <ln/ln.h>

#include "ln_test.h"

struct entry {
    int code;
    const char* name;
    const char* message;
};

static const struct entry table[] = {
#define ENTRY(name, code, message) {LN_##name, #name, message},
    LN_ERRNO_MAP(ENTRY)
#undef ENTRY
};
enum { ENTRIES = sizeof(table) / sizeof(table[0]) };

static void test_count_matches_header(void) { LN_CHECK_EQ(ln_error_count(), ENTRIES); }

static void test_codes_negative_unique_contiguous(void)
{
    int seen[ENTRIES] = {0};
    for (int i = 0; i < ENTRIES; i++) {
        int code = table[i].code;
        LN_CHECK(code < 0 && code >= -ENTRIES);
        if (code < 0 && code >= -ENTRIES)
            seen[-code - 1]++;
    }
    for (int i = 0; i < ENTRIES; i++)
        LN_CHECK_EQ(seen[i], 1); /* each of -1 .. -ENTRIES exactly once */
}

static void test_names_unique(void)
{
    for (int i = 0; i < ENTRIES; i++)
        for (int j = i + 1; j < ENTRIES; j++)
            LN_CHECK(strcmp(table[i].name, table[j].name) != 0);
}

static void test_library_strings_match_table(void)
{
    for (int i = 0; i < ENTRIES; i++) {
        LN_CHECK_STREQ(ln_error_name(table[i].code), table[i].name);
        LN_CHECK_STREQ(ln_strerror(table[i].code), table[i].message);
        LN_CHECK(table[i].message[0] != '\0');
        LN_CHECK(strcmp(table[i].message, "unknown error") != 0);
    }
}

static void test_ok(void)
{
    LN_CHECK_EQ(LN_OK, 0);
    LN_CHECK_STREQ(ln_error_name(LN_OK), "OK");
    LN_CHECK_STREQ(ln_strerror(LN_OK), "success");
}

static void test_unknown_codes(void)
{
    const int unknown[] = {1, 42, -ENTRIES - 1, -1000, INT_MIN, INT_MAX};
    for (size_t i = 0; i < sizeof(unknown) / sizeof(unknown[0]); i++) {
        LN_CHECK(ln_error_name(unknown[i]) == NULL);
        LN_CHECK_STREQ(ln_strerror(unknown[i]), "unknown error");
    }
}

int main(void)
{
    LN_TEST_RUN(test_count_matches_header);
    LN_TEST_RUN(test_codes_negative_unique_contiguous);
    LN_TEST_RUN(test_names_unique);
    LN_TEST_RUN(test_library_strings_match_table);
    LN_TEST_RUN(test_ok);
    LN_TEST_RUN(test_unknown_codes);
    LN_TEST_EXIT();
}
