/* test_param_core.c — parameter blocks without a manager (libln's internals, linked
 * statically): the JSON reader and writer, every check a value goes through, set/get/reset
 * as the service answers them, the loop's update() (an override visible at the next update
 * exactly once, several at once together, never torn while a writer thread sets values), the
 * initial overrides of $LN_PARAMETERS, and update() making no system call at all (a child
 * process runs it under a seccomp filter that kills it on any system call but exit). */
#define _GNU_SOURCE 1

#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "param_internal.h"

#include "ln_test.h"

/* ---- JSON ---- */

static void test_json_reader(void)
{
    const char* p = " {\"a\\u00e9\\ud83d\\ude00\": [1, -2.5e3, true], \"b\": \"x\\\"y\"} tail";
    int first = 1;
    char key[32];
    LN_CHECK_EQ(ln_pj_open(&p, '{'), 0);
    LN_CHECK_EQ(ln_pj_next_member(&p, &first, key, sizeof key), 1);
    LN_CHECK_STREQ(key, "a\xc3\xa9\xf0\x9f\x98\x80");
    LN_CHECK_EQ(ln_pj_skip(&p), 0);
    LN_CHECK_EQ(ln_pj_next_member(&p, &first, key, sizeof key), 1);
    char value[8];
    size_t len;
    LN_CHECK_EQ(ln_pj_string(&p, value, sizeof value, &len), 0);
    LN_CHECK_STREQ(value, "x\"y");
    LN_CHECK_EQ(ln_pj_next_member(&p, &first, key, sizeof key), 0);
    LN_CHECK_STREQ(ln_pj_ws(p), "tail");

    const char* bad[] = {"[1,]", "{\"a\" 1}", "[01]", "[1.]", "\"\\x\"", "{\"a\":1,}",
                         "[",    "\"abc",     "-",    "1e",   "nul"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        const char* q = bad[i];
        LN_CHECK_EQ(ln_pj_skip(&q), -1);
    }
    char deep[200];
    memset(deep, '[', sizeof deep - 1);
    deep[sizeof deep - 1] = '\0';
    const char* d = deep;
    LN_CHECK_EQ(ln_pj_skip(&d), -1); /* too deep: refused, not a stack overflow */
}

static void test_json_writer(void)
{
    ln_pbuf b;
    ln_pbuf_init(&b);
    ln_pbuf_double(&b, 0.1, 0);
    ln_pbuf_raw(&b, " ", 1);
    ln_pbuf_double(&b, (float)0.1, 1);
    ln_pbuf_raw(&b, " ", 1);
    ln_pbuf_double(&b, 3, 0);
    ln_pbuf_raw(&b, " ", 1);
    ln_pbuf_double(&b, NAN, 0);
    ln_pbuf_raw(&b, " ", 1);
    ln_pbuf_double(&b, -INFINITY, 0);
    ln_pbuf_raw(&b, " ", 1);
    ln_pbuf_quote(&b, "a\"\n\xff\xc3\xa9", 6);
    LN_CHECK_STREQ(b.data, "0.1 0.1 3.0 \"NaN\" \"-Infinity\" \"a\\\"\\u000a\\ufffd\xc3\xa9\"");
    ln_pbuf_free(&b);
}

/* ---- a block of every kind of parameter ---- */

struct vars {
    double kp_in[3], kp[3];
    double gain; /* no input: its default */
    float f;
    int32_t i32;
    uint8_t flag;
    uint64_t big;
    int8_t small;
    char label[8];
    int16_t fixed; /* read-only */
};

static int refuse_13(ln_parameter_block* blk, int index, const char* name, const void* value,
                     char* reason, size_t size, void* user)
{
    (void)blk;
    (void)index;
    (void)user;
    if (strcmp(name, "i32") == 0) {
        int32_t v;
        memcpy(&v, value, 4);
        if (v == 13) {
            snprintf(reason, size, "13 brings bad luck");
            return 1;
        }
    }
    return 0;
}

static ln_parameter_block* make_block(struct vars* v)
{
    memset(v, 0, sizeof *v);
    v->kp_in[0] = 1, v->kp_in[1] = 2, v->kp_in[2] = 3;
    v->gain = 0.5;
    snprintf(v->label, sizeof v->label, "init");
    ln_parameter_block* b = ln_param_new(NULL, "gains", "test.parameters.gains");
    ln_parameter_desc d[] = {
        {.name = "kp",
         .type = "double",
         .count = 3,
         .input = v->kp_in,
         .output = v->kp,
         .flags = LN_PARAMETER_MIN | LN_PARAMETER_MAX,
         .min = 0,
         .max = 100,
         .description = "stiffness"},
        {.name = "gain",
         .type = "float64_t",
         .output = &v->gain,
         .flags = LN_PARAMETER_MAX,
         .max = 1},
        {.name = "f", .type = "float", .output = &v->f},
        {.name = "i32", .type = "int", .output = &v->i32},
        {.name = "flag", .type = "uint8_t", .output = &v->flag},
        {.name = "big", .type = "uint64_t", .output = &v->big},
        {.name = "small", .type = "int8_t", .output = &v->small},
        {.name = "label", .type = "char", .count = 8, .output = v->label},
        {.name = "fixed", .type = "int16_t", .output = &v->fixed, .flags = LN_PARAMETER_READ_ONLY},
    };
    for (size_t i = 0; i < sizeof d / sizeof d[0]; i++)
        LN_CHECK_EQ(ln_parameter_block_add(b, &d[i]), (long long)i);
    LN_CHECK_EQ(ln_parameter_block_set_validator(b, refuse_13, NULL), LN_OK);
    LN_CHECK_EQ(ln_param_prepare(b), LN_OK);
    return b;
}

/* A request; returns 0 or -1, err and the result text in *result (to free). */
static int req(ln_parameter_block* b, const char* op, const char* name, const char* value,
               ln_param_err* err, char** result)
{
    ln_pbuf out;
    ln_pbuf_init(&out);
    memset(err, 0, sizeof *err);
    err->kind = "";
    int rc = ln_param_request(b, op, name, value, &out, err);
    if (result != NULL)
        *result = out.data ? strdup(out.data) : strdup("");
    ln_pbuf_free(&out);
    return rc;
}

static void expect_refusal(ln_parameter_block* b, const char* name, const char* value,
                           const char* kind, const char* reason_part)
{
    ln_param_err err;
    LN_CHECK_EQ(req(b, "set", name, value, &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, kind);
    if (strstr(err.reason, reason_part) == NULL) {
        fprintf(stderr, "    set %s = %s: reason \"%s\" lacks \"%s\"\n", name, value, err.reason,
                reason_part);
        LN_CHECK(0);
    }
}

static void test_add_checks(void)
{
    double x = 0;
    ln_parameter_block* b = ln_param_new(NULL, "b", "s");
    ln_parameter_desc ok = {.name = "x", .type = "double", .output = &x};
    LN_CHECK_EQ(ln_parameter_block_add(b, &ok), 0);
    LN_CHECK_EQ(ln_parameter_block_add(b, &ok), LN_EEXIST);
    ln_parameter_desc bad = ok;
    bad.name = "y";
    bad.type = "bool";
    LN_CHECK_EQ(ln_parameter_block_add(b, &bad), LN_EINVAL);
    bad.type = "double";
    bad.output = NULL;
    LN_CHECK_EQ(ln_parameter_block_add(b, &bad), LN_EINVAL);
    bad.output = &x;
    bad.name = "sp ace";
    LN_CHECK_EQ(ln_parameter_block_add(b, &bad), LN_EINVAL);
    bad.name = "y";
    bad.flags = LN_PARAMETER_MIN | LN_PARAMETER_MAX;
    bad.min = 2, bad.max = 1;
    LN_CHECK_EQ(ln_parameter_block_add(b, &bad), LN_EINVAL);
    bad.type = "char", bad.min = 0;
    LN_CHECK_EQ(ln_parameter_block_add(b, &bad), LN_EINVAL); /* no range for strings */
    LN_CHECK_EQ(ln_param_prepare(b), LN_OK);
    ln_parameter_desc late = {.name = "z", .type = "double", .output = &x};
    LN_CHECK_EQ(ln_parameter_block_add(b, &late), LN_EBUSY);
    LN_CHECK_EQ(ln_parameter_block_destroy(b), LN_OK);
}

static void test_value_checks(void)
{
    struct vars v;
    ln_parameter_block* b = make_block(&v);
    ln_param_err err;
    /* accepted: an integer for a float, a whole float for an integer, true for uint8 */
    LN_CHECK_EQ(req(b, "set", "kp", "[4, 5.5, 1e1]", &err, NULL), 0);
    LN_CHECK_EQ(req(b, "set", "i32", "-7.0", &err, NULL), 0);
    LN_CHECK_EQ(req(b, "set", "flag", "true", &err, NULL), 0);
    LN_CHECK_EQ(req(b, "set", "big", "18446744073709551615", &err, NULL), 0);
    LN_CHECK_EQ(req(b, "set", "f", "\"NaN\"", &err, NULL), 0);
    LN_CHECK_EQ(req(b, "set", "label", "\"\\u00e9t\\u00e9\"", &err, NULL), 0);
    LN_CHECK_EQ(ln_parameter_block_update(b), 6);
    LN_CHECK(v.kp[0] == 4 && v.kp[1] == 5.5 && v.kp[2] == 10);
    LN_CHECK_EQ(v.i32, -7);
    LN_CHECK_EQ(v.flag, 1);
    LN_CHECK(v.big == UINT64_MAX);
    LN_CHECK(isnan(v.f));
    LN_CHECK_STREQ(v.label, "\xc3\xa9t\xc3\xa9");

    expect_refusal(b, "kp", "[1, 2]", "size", "expected 3 values (double[3]), got 2");
    expect_refusal(b, "kp", "[1, 2, 3, 4]", "size", "4 values do not fit in double[3]");
    expect_refusal(b, "kp", "[1, 2, 300]", "range", "kp[2]: 300 is above the maximum 100");
    expect_refusal(b, "kp", "[-1, 2, 3]", "range", "kp[0]: -1 is below the minimum 0");
    expect_refusal(b, "kp", "3", "type", "expected a list of 3 values");
    expect_refusal(b, "kp", "[1, \"a\", 3]", "type", "kp[1]: expected a number");
    expect_refusal(b, "gain", "\"fast\"", "type", "expected a number (double)");
    expect_refusal(b, "gain", "[1]", "type", "not a list");
    expect_refusal(b, "gain", "1.5", "range", "above the maximum 1");
    expect_refusal(b, "i32", "2.5", "type", "expected an integer (int32_t), not 2.5");
    expect_refusal(b, "i32", "2147483648", "range", "out of range for int32_t");
    expect_refusal(b, "i32", "13", "refused", "i32: 13 brings bad luck");
    expect_refusal(b, "small", "-129", "range", "-128..127");
    expect_refusal(b, "big", "-1", "range", "out of range for uint64_t");
    expect_refusal(b, "big", "18446744073709551616", "range", "out of range");
    expect_refusal(b, "f", "1e39", "range", "out of range for float");
    expect_refusal(b, "f", "true", "type", "expected a number (float), not true");
    expect_refusal(b, "label", "\"123456789\"", "size", "9 bytes does not fit in char[8]");
    expect_refusal(b, "label", "5", "type", "expected a string");
    expect_refusal(b, "fixed", "1", "read_only", "fixed is read-only");
    expect_refusal(b, "nope", "1", "not_found", "no parameter \"nope\"");
    expect_refusal(b, "gain", "0.5 0.6", "bad_request", "text after the value");
    expect_refusal(b, "gain", "", "bad_request", "no value given");
    expect_refusal(b, "gain", "[1", "type", "expected a number");
    LN_CHECK_EQ(req(b, "frob", "", "", &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, "bad_request");
    LN_CHECK_EQ(err.code, LN_EINVAL);
    /* none of the refusals changed anything */
    LN_CHECK_EQ(ln_parameter_block_update(b), 0);
    LN_CHECK(v.kp[0] == 4 && v.i32 == -7);
    ln_parameter_block_destroy(b);
}

static void test_set_update_reset(void)
{
    struct vars v;
    ln_parameter_block* b = make_block(&v);
    ln_param_err err;
    LN_CHECK_EQ(ln_parameter_block_update(b), 0);
    LN_CHECK(v.kp[0] == 1 && v.kp[2] == 3); /* the input */
    LN_CHECK(v.gain == 0.5);
    LN_CHECK_EQ(req(b, "set", "gain", "0.25", &err, NULL), 0);
    LN_CHECK(v.gain == 0.5); /* not before the next update */
    LN_CHECK_EQ(ln_parameter_block_update(b), 1);
    LN_CHECK(v.gain == 0.25);
    LN_CHECK_EQ(ln_parameter_block_changed(b, 1), 1);
    LN_CHECK_EQ(ln_parameter_block_changed(b, 0), 0);
    LN_CHECK_EQ(ln_parameter_block_update(b), 0); /* exactly once */
    LN_CHECK_EQ(ln_parameter_block_changed(b, 1), 0);
    LN_CHECK_EQ(ln_parameter_block_changed(b, 99), LN_EINVAL);

    /* several at once: all in one update, or none if one is refused */
    char* result;
    LN_CHECK_EQ(req(b, "set", "", "{\"kp\": [7, 8, 9], \"i32\": 5}", &err, &result), 0);
    LN_CHECK(strstr(result, "\"set\": [\"kp\", \"i32\"]") != NULL);
    free(result);
    LN_CHECK_EQ(req(b, "set", "", "{\"kp\": [1, 1, 1], \"i32\": 13}", &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, "refused");
    LN_CHECK_EQ(req(b, "set", "", "{\"kp\": [1, 1, 1], \"kp\": [2, 2, 2]}", &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, "bad_request");
    LN_CHECK_EQ(ln_parameter_block_update(b), 2);
    LN_CHECK(v.kp[0] == 7 && v.kp[2] == 9 && v.i32 == 5);
    v.kp_in[0] = 42; /* the program's input does not reach an overridden output */
    LN_CHECK_EQ(ln_parameter_block_update(b), 0);
    LN_CHECK(v.kp[0] == 7);

    /* get: the loop's values as of its next update */
    LN_CHECK_EQ(req(b, "get", "kp", "{\"wait\": 0}", &err, &result), 0);
    LN_CHECK(strstr(result, "\"live\": false") != NULL); /* nobody updated within 0 s */
    free(result);
    LN_CHECK_EQ(req(b, "get", "kp", "{\"wait\": -1}", &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, "bad_request");

    /* reset: back to the input (or the default) */
    LN_CHECK_EQ(req(b, "reset", "kp", "", &err, &result), 0);
    LN_CHECK(strstr(result, "\"reset\": [\"kp\"]") != NULL);
    free(result);
    LN_CHECK_EQ(ln_parameter_block_update(b), 1);
    LN_CHECK(v.kp[0] == 42 && v.kp[1] == 2);
    LN_CHECK_EQ(req(b, "reset", "", "", &err, NULL), 0);
    LN_CHECK_EQ(ln_parameter_block_update(b), 2); /* gain and i32 */
    LN_CHECK(v.gain == 0.5 && v.i32 == 0);
    LN_CHECK_EQ(req(b, "reset", "", "", &err, NULL), 0); /* nothing overridden: no change */
    LN_CHECK_EQ(ln_parameter_block_update(b), 0);

    /* several at once, by a list of names */
    LN_CHECK_EQ(req(b, "set", "", "{\"gain\": 0.75, \"i32\": 8, \"flag\": 1}", &err, NULL), 0);
    LN_CHECK_EQ(req(b, "reset", "", "[\"gain\", \"nope\"]", &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, "not_found");
    LN_CHECK_EQ(req(b, "reset", "", "[\"gain\", 3]", &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, "bad_request");
    LN_CHECK_EQ(req(b, "reset", "", "[\"gain\", \"i32\"]", &err, &result), 0);
    LN_CHECK(strstr(result, "\"generation\": 6, \"reset\": [\"gain\", \"i32\"]") != NULL);
    free(result);
    LN_CHECK_EQ(ln_parameter_block_update(b), 3); /* both requests since the last update */
    LN_CHECK(v.gain == 0.5 && v.i32 == 0 && v.flag == 1);
    LN_CHECK_EQ(req(b, "reset", "", "", &err, NULL), 0);
    ln_parameter_block_update(b);

    /* the change stream: every change since a generation, with the values of a set */
    LN_CHECK_EQ(req(b, "changes", "", "{\"since\": 2}", &err, &result), 0);
    LN_CHECK(
        strstr(result, "{\"generation\": 7, \"oldest\": 1, \"changes\": [{\"generation\": 3, ") !=
        NULL);
    LN_CHECK(strstr(result, "\"op\": \"reset\", \"parameters\": [\"kp\"]}") != NULL);
    LN_CHECK(strstr(result, "\"generation\": 2,") == NULL);
    free(result);
    LN_CHECK_EQ(req(b, "changes", "", "", &err, &result), 0);
    LN_CHECK(strstr(result, "\"op\": \"set\", \"parameters\": [\"kp\", \"i32\"], "
                            "\"values\": {\"kp\": [7.0, 8.0, 9.0], \"i32\": 5}}") != NULL);
    free(result);
    LN_CHECK_EQ(req(b, "changes", "", "{\"since\": -1}", &err, NULL), -1);
    LN_CHECK_STREQ(err.kind, "bad_request");

    /* list: descriptors with values, nothing pending */
    LN_CHECK_EQ(req(b, "set", "gain", "1", &err, NULL), 0);
    LN_CHECK_EQ(req(b, "list", "gain", "", &err, &result), 0);
    LN_CHECK(strstr(result, "\"name\": \"gain\", \"type\": \"double\", \"count\": 1") != NULL);
    LN_CHECK(strstr(result, "\"max\": 1.0") != NULL);
    LN_CHECK(strstr(result, "\"overridden\": true, \"override\": 1.0, \"source\": \"set\"") !=
             NULL);
    LN_CHECK(strstr(result, "\"pending\": true") != NULL);
    free(result);
    ln_parameter_block_update(b);
    LN_CHECK_EQ(req(b, "list", "", "", &err, &result), 0);
    LN_CHECK(strstr(result, "\"pending\": true") == NULL);
    LN_CHECK(strstr(result, "\"name\": \"fixed\"") != NULL);
    free(result);
    ln_parameter_block_destroy(b);
}

/* ---- a writer thread against the loop: whole requests or nothing ---- */

struct race {
    ln_parameter_block* b;
    int sets;
    int failed;
};

static void* writer(void* arg)
{
    struct race* r = arg;
    for (int k = 1; k <= r->sets; k++) {
        char value[64];
        int x = 2 * k; /* even: never the validator's 13 */
        snprintf(value, sizeof value, "{\"kp\": [%d, %d, %d], \"i32\": %d}", x % 100, x % 100,
                 x % 100, x);
        ln_param_err err;
        if (req(r->b, "set", "", value, &err, NULL) != 0)
            r->failed++;
    }
    return NULL;
}

/* gets (the loop's live values) while the loop and the writer run */
static void* reader(void* arg)
{
    struct race* r = arg;
    for (int k = 0; k < 200; k++) {
        ln_param_err err;
        char* result = NULL;
        if (req(r->b, "get", "", "{\"wait\": 1}", &err, &result) != 0 ||
            strstr(result, "\"live\": true") == NULL)
            r->failed++;
        free(result);
    }
    return NULL;
}

static void test_never_torn(void)
{
    struct vars v;
    ln_parameter_block* b = make_block(&v);
    struct race r = {b, 20000, 0}, g = {b, 0, 0};
    pthread_t t, tg;
    pthread_create(&t, NULL, writer, &r);
    pthread_create(&tg, NULL, reader, &g);
    int last = 0, torn = 0, backwards = 0, changes = 0;
    while (last < 2 * r.sets) {
        int n = ln_parameter_block_update(b);
        if (n > 0)
            changes++;
        if (v.i32 > 0 /* the first set arrived */
            && (v.kp[0] != v.kp[1] || v.kp[1] != v.kp[2] || (int)v.kp[0] != v.i32 % 100))
            torn++;
        if (v.i32 < last)
            backwards++;
        last = v.i32;
    }
    pthread_join(t, NULL);
    while (pthread_tryjoin_np(tg, NULL) != 0) /* the loop serves the gets to their end */
        ln_parameter_block_update(b);
    LN_CHECK_EQ(r.failed, 0);
    LN_CHECK_EQ(g.failed, 0);
    LN_CHECK_EQ(torn, 0);
    LN_CHECK_EQ(backwards, 0);
    LN_CHECK(changes >= 1 && changes <= r.sets);
    LN_CHECK_EQ(ln_parameter_block_update(b), 0);
    ln_parameter_block_destroy(b);
}

/* ---- $LN_PARAMETERS ---- */

static void test_initial_overrides(void)
{
    setenv("LN_PARAMETERS",
           "{\"other\": {\"x\": 1}, \"gains\": {\"gain\": 0.75, \"kp\": [9, 9, 900], "
           "\"nope\": 1, \"label\": \"cfg\", \"i32\": 13}}",
           1);
    struct vars v;
    ln_parameter_block* b = make_block(&v);
    unsetenv("LN_PARAMETERS");
    LN_CHECK_EQ(ln_parameter_block_update(b), 2); /* gain and label; kp, i32 refused */
    LN_CHECK(v.gain == 0.75);
    LN_CHECK_STREQ(v.label, "cfg");
    LN_CHECK(v.kp[2] == 3);
    ln_param_err err;
    char* result;
    LN_CHECK_EQ(req(b, "list", "label", "", &err, &result), 0);
    LN_CHECK(strstr(result, "\"source\": \"config\"") != NULL);
    LN_CHECK(strstr(result, "kp[2]: 900 is above the maximum 100") != NULL);
    LN_CHECK(strstr(result, "no parameter \\\"nope\\\"") != NULL);
    LN_CHECK(strstr(result, "13 brings bad luck") != NULL);
    free(result);
    ln_parameter_block_destroy(b);
}

/* ---- no system call in update() ---- */

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define UNDER_SANITIZER 1
#endif

#if defined(__x86_64__) && !defined(UNDER_SANITIZER)
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <stddef.h>
#include <sys/prctl.h>
#include <sys/syscall.h>

/* Kills the process on every system call but exit and exit_group. */
static int forbid_syscalls(void)
{
    struct sock_filter filter[] = {
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, arch)),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AUDIT_ARCH_X86_64, 1, 0),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_KILL_PROCESS),
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, nr)),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_exit_group, 2, 0),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_exit, 1, 0),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_KILL_PROCESS),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
    };
    struct sock_fprog prog = {.len = sizeof filter / sizeof filter[0], .filter = filter};
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0)
        return -1;
    return prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &prog);
}

static void test_update_makes_no_syscall(void)
{
    struct vars v;
    ln_parameter_block* b = make_block(&v);
    ln_param_err err;
    LN_CHECK_EQ(req(b, "set", "", "{\"kp\": [5, 6, 7], \"gain\": 0.125}", &err, NULL), 0);
    fflush(NULL);
    pid_t child = fork();
    if (child == 0) {
        if (forbid_syscalls() != 0)
            syscall(SYS_exit_group, 3);
        int changed = ln_parameter_block_update(b); /* takes the pending change */
        for (int i = 0; i < 100000; i++)
            changed += ln_parameter_block_update(b);
        int ok = changed == 2 && v.kp[1] == 6 && v.gain == 0.125;
        syscall(SYS_exit_group, ok ? 0 : 4);
    }
    int status = 0;
    LN_CHECK_EQ(waitpid(child, &status, 0), child);
    if (WIFSIGNALED(status))
        fprintf(stderr, "    update() made a system call: killed by signal %d\n", WTERMSIG(status));
    LN_CHECK(WIFEXITED(status));
    LN_CHECK_EQ(WEXITSTATUS(status), 0);
    ln_parameter_block_destroy(b);
}
#else
static void test_update_makes_no_syscall(void)
{
    printf("skip (seccomp check: x86-64 without ASan/TSan only)\n");
}
#endif

int main(void)
{
    LN_TEST_RUN(test_json_reader);
    LN_TEST_RUN(test_json_writer);
    LN_TEST_RUN(test_add_checks);
    LN_TEST_RUN(test_value_checks);
    LN_TEST_RUN(test_set_update_reset);
    LN_TEST_RUN(test_never_torn);
    LN_TEST_RUN(test_initial_overrides);
    LN_TEST_RUN(test_update_makes_no_syscall);
    LN_TEST_EXIT();
}
