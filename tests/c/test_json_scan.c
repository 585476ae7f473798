/* test_json_scan.c — the JSON reading ln_control does on the manager's CONTROL answers:
 * members found past nested values and escaped strings, booleans and strings decoded,
 * malformed text reported as missing; and quoting of what ln_logger_* sends. */
#define _GNU_SOURCE 1

#include <string.h>

/* Internal (hidden in libln.so): compiled in. */
#include "../../libln/src/json_scan.c"

#include "ln_test.h"

static void test_members_past_nested_values(void)
{
    const char* j = "{\"a\": {\"ok\": false, \"x\": [1, {\"ok\": 0}]}, \"s\": \"}\\\"{\","
                    " \"ok\": true, \"error\": \"\"}";
    LN_CHECK_EQ(ln_json_bool(j, "ok"), 1);
    char out[64];
    LN_CHECK_EQ(ln_json_string(j, "s", out, sizeof out), 0);
    LN_CHECK(strcmp(out, "}\"{") == 0);
    LN_CHECK_EQ(ln_json_string(j, "error", out, sizeof out), 0);
    LN_CHECK(strcmp(out, "") == 0);
    LN_CHECK_EQ(ln_json_bool(j, "missing"), -1);
    LN_CHECK_EQ(ln_json_string(j, "ok", out, sizeof out), -1); /* not a string */
}

static void test_refusal(void)
{
    const char* j = "{\"ok\": false, \"error\": \"no logger 'x'\\n(loggers: \\u00e9, a\\\\b)\","
                    " \"code\": \"ENOTFOUND\"}";
    LN_CHECK_EQ(ln_json_bool(j, "ok"), 0);
    char out[64];
    LN_CHECK_EQ(ln_json_string(j, "error", out, sizeof out), 0);
    LN_CHECK(strcmp(out, "no logger 'x'\n(loggers: \xc3\xa9, a\\b)") == 0);
    char small[6];
    LN_CHECK_EQ(ln_json_string(j, "code", small, sizeof small), 0); /* cut, NUL-terminated */
    LN_CHECK(strcmp(small, "ENOTF") == 0);
}

static void test_malformed(void)
{
    const char* bad[] = {"",
                         "[]",
                         "{",
                         "{\"ok\"",
                         "{\"ok\" true}",
                         "{\"a\": \"x, \"ok\": true",
                         "{\"a\": [1, 2, \"ok\": true}",
                         "null",
                         "{\"ok\": tru"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        LN_CHECK_EQ(ln_json_bool(bad[i], "ok"), -1);
    char out[8];
    LN_CHECK_EQ(ln_json_string("{\"e\": \"unterminated", "e", out, sizeof out), -1);
}

static void test_quote(void)
{
    char out[64];
    size_t n = ln_json_quote("a\"b\\c\n\x01/", out, sizeof out);
    LN_CHECK(strcmp(out, "\"a\\\"b\\\\c\\u000a\\u0001/\"") == 0);
    LN_CHECK_EQ(n, strlen(out));
    char small[4];
    LN_CHECK_EQ(ln_json_quote("abcdef", small, sizeof small), 8); /* like snprintf */
    LN_CHECK(strcmp(small, "\"ab") == 0);
    LN_CHECK_EQ(ln_json_quote("x", NULL, 0), 3);
    /* what is quoted reads back */
    char doc[128], back[64];
    snprintf(doc, sizeof doc, "{\"p\": %s}", out);
    LN_CHECK_EQ(ln_json_string(doc, "p", back, sizeof back), 0);
    LN_CHECK(strcmp(back, "a\"b\\c\n\x01/") == 0);
}

/* The array walk events use for their handler lists. */
static void test_arrays(void)
{
    const char* j = "{\"n\": 1, \"h\": [ {\"s\": \"a]\"}, \"x\" ,[1,2], {} ], \"e\": []}";
    const char* pos = ln_json_array(j, "h");
    LN_CHECK(pos != NULL);
    const char* start;
    size_t len;
    const char* want[] = {"{\"s\": \"a]\"}", "\"x\"", "[1,2]", "{}"};
    for (size_t i = 0; i < 4; i++) {
        LN_CHECK_EQ(ln_json_next(&pos, &start, &len), 1);
        LN_CHECK(len == strlen(want[i]) && memcmp(start, want[i], len) == 0);
    }
    LN_CHECK_EQ(ln_json_next(&pos, &start, &len), 0);
    pos = ln_json_array(j, "e");
    LN_CHECK(pos != NULL);
    LN_CHECK_EQ(ln_json_next(&pos, &start, &len), 0);
    LN_CHECK(ln_json_array(j, "n") == NULL); /* not an array */
    LN_CHECK(ln_json_array(j, "missing") == NULL);
    const char* bad[] = {"{\"h\": [1 2]}", "{\"h\": [1,]}", "{\"h\": [\"open]}"};
    for (size_t i = 0; i < 3; i++) {
        pos = ln_json_array(bad[i], "h");
        int rc = 1;
        while (pos != NULL && rc == 1)
            rc = ln_json_next(&pos, &start, &len);
        LN_CHECK_EQ(rc, -1);
    }
}

int main(void)
{
    LN_TEST_RUN(test_arrays);
    LN_TEST_RUN(test_members_past_nested_values);
    LN_TEST_RUN(test_refusal);
    LN_TEST_RUN(test_malformed);
    LN_TEST_RUN(test_quote);
    LN_TEST_EXIT();
}
