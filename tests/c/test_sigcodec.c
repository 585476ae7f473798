/* test_sigcodec.c — the signature codec: parsing every generated signature, round trips of
 * structs with nested dynamic data, hostile and truncated wire data, limits, bad signatures
 * with their column, and a deterministic mutation fuzz loop (run under ASan/UBSan too).
 * Links the static libln to reach the internal codec. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ln_test.h"
#include "sigcodec.h"
#include "sigcodec_messages.h"

#define MAX LN_SIG_DEFAULT_MAX_BYTES

static ln_sig* parse(const char* text)
{
    ln_sig* sig = NULL;
    int rc = ln_sig_parse(text, &sig);
    LN_CHECK_EQ(rc, LN_OK);
    if (rc != LN_OK)
        fprintf(stderr, "    %s\n", ln_last_error());
    return sig;
}

/* Both sections of a service or event signature. */
static void parse_service(const char* text, ln_sig** req, ln_sig** resp)
{
    char *a = NULL, *b = NULL;
    LN_CHECK_EQ(ln_sig_split(text, &a, &b), LN_OK);
    *req = a ? parse(a) : NULL;
    *resp = b ? parse(b) : NULL;
    free(a);
    free(b);
}

static void test_parse_generated(void)
{
    static const struct {
        const char* text;
        size_t size;
    } messages[] = {
        {LN_STRING_SIGNATURE, sizeof(ln_string_t)},
        {ROBOT_JOINT_STATE_SIGNATURE, sizeof(robot_joint_state_t)},
        {LNTEST_DEEP_SIGNATURE, sizeof(lntest_deep_t)},
        {LNTEST_OUTER_SIGNATURE, sizeof(lntest_outer_t)},
        {LNTEST_MIDDLE_SIGNATURE, sizeof(lntest_middle_t)},
        {LNTEST_ALL_TYPES_SIGNATURE, sizeof(lntest_all_types_t)},
        {LNTEST_MIXED_CASE_SIGNATURE, sizeof(lntest_Mixed_Case_t)},
        {LNTEST_EXPRESSIONS_SIGNATURE, sizeof(lntest_expressions_t)},
    };
    for (size_t i = 0; i < LN_ARRAY_SIZE(messages); i++) {
        ln_sig* sig = parse(messages[i].text);
        if (sig != NULL)
            LN_CHECK_EQ(ln_sig_size(sig), messages[i].size);
        ln_sig_free(sig);
    }
    static const struct {
        const char* text;
        size_t req, resp;
    } services[] = {
        {ROBOT_PLAN_PATH_SIGNATURE, ROBOT_PLAN_PATH_REQUEST_SIZE, ROBOT_PLAN_PATH_RESPONSE_SIZE},
        {ROBOT_SET_GAINS_SIGNATURE, ROBOT_SET_GAINS_REQUEST_SIZE, ROBOT_SET_GAINS_RESPONSE_SIZE},
        /* the example of docs/message_definitions.md */
        {"double 8 7,double 8 7,uint32_t 4 1,char* 1 1|uint8_t 1 1,uint32_t 4 1,char* 1 1", 124,
         13},
        {LNTEST_QUERY_SIGNATURE, LNTEST_QUERY_REQUEST_SIZE, LNTEST_QUERY_RESPONSE_SIZE},
        {LNTEST_ALARM_SIGNATURE, LNTEST_ALARM_CONNECT_SIZE, LNTEST_ALARM_CALL_SIZE},
        {LNTEST_EMPTY_REQUEST_SIGNATURE, 0, LNTEST_EMPTY_REQUEST_RESPONSE_SIZE},
        {LNTEST_NOTHING_SIGNATURE, 0, 0},
    };
    for (size_t i = 0; i < LN_ARRAY_SIZE(services); i++) {
        ln_sig *req, *resp;
        parse_service(services[i].text, &req, &resp);
        if (req != NULL && resp != NULL) {
            LN_CHECK_EQ(ln_sig_size(req), services[i].req);
            LN_CHECK_EQ(ln_sig_size(resp), services[i].resp);
        }
        ln_sig_free(req);
        ln_sig_free(resp);
    }
}

static void check_bad(const char* text, const char* where)
{
    ln_sig* sig = (ln_sig*)1;
    LN_CHECK_EQ(ln_sig_parse(text, &sig), LN_EMD);
    LN_CHECK(sig == NULL);
    if (strstr(ln_last_error(), where) == NULL) {
        ln_test_fail(__FILE__, __LINE__, "error text names the position");
        fprintf(stderr, "    \"%s\": \"%s\" lacks \"%s\"\n", text, ln_last_error(), where);
    }
}

static void test_bad_signatures(void)
{
    check_bad("double 8 1,int33_t 4 1", "column 12: unknown type 'int33_t'");
    check_bad("double 4 1", "column 8: size of double is 8, not 4");
    check_bad("[double 8 1,char 1 2] 11 1", "column 23: record size 11, but its items take 10");
    check_bad("char* 1 1", "column 1: dynamic field without its 'uint32_t 4 1' count");
    check_bad("int32_t 4 1,char* 1 1", "column 13: dynamic field without");
    check_bad("uint32_t 4 2,char* 1 1", "column 14: dynamic field without");
    check_bad("uint32_t 4 1,char* 1 2", "column 22: a dynamic field has count 1");
    check_bad("uint32_t 4 1,[char 1 1* 1 1", "column 23: expected ',' or ']', found '*'");
    check_bad("[double 8 1 8 1", "column 12: expected ',' or ']', found ' '");
    check_bad("[double 8 1", "column 12: expected ',' or ']', found end of signature");
    check_bad("double 8 1] 8 1", "column 11: expected ',' or the end, found ']'");
    check_bad("double 8 1,", "column 12: expected a type or '[', found end");
    check_bad(",double 8 1", "column 1: expected a type or '[', found ','");
    check_bad("[] 0 1", "column 1: empty record");
    check_bad(" ", "column 1: expected a type or '['");
    check_bad("double  8 1", "column 8: expected the size");
    check_bad("double 8", "column 9: expected ' ' before the count");
    check_bad("double 8 0", "column 10: count must be at least 1");
    check_bad("double 8 99999999999", "column 10: count larger than");
    check_bad("char 1 1073741824,char 1 1", "column 19: struct larger than");
    check_bad("double 8 1|int8_t 1 1", "column 11: expected ',' or the end, found '|'");
    /* deeper than LN_SIG_MAX_DEPTH */
    char deep[4 * LN_SIG_MAX_DEPTH + 64];
    size_t n = 0;
    for (int i = 0; i <= LN_SIG_MAX_DEPTH; i++)
        deep[n++] = '[';
    deep[n] = '\0';
    check_bad(deep, "nested deeper than 32");

    char *a = (char*)1, *b = (char*)1;
    LN_CHECK_EQ(ln_sig_split("double 8 1", &a, &b), LN_EMD);
    LN_CHECK(a == NULL && b == NULL);
    LN_CHECK_EQ(ln_sig_split("|double 8 1|", &a, &b), LN_EMD);
    LN_CHECK(strstr(ln_last_error(), "column 12") != NULL);
    LN_CHECK_EQ(ln_sig_split("a|b", &a, &b), LN_OK);
    LN_CHECK_STREQ(a, "a");
    LN_CHECK_STREQ(b, "b");
    free(a);
    free(b);
}

static int encode(const ln_sig* sig, const void* msg, ln_wbuf* out)
{
    ln_wbuf_reset(out);
    int rc = ln_sig_encode(sig, msg, out, MAX);
    if (rc != LN_OK)
        fprintf(stderr, "    encode: %s\n", ln_last_error());
    return rc;
}

/* ---- robot/plan_path: strings in an array of records, an array of nested records ---- */

static const char* names[] = {"joint_limits", "", "self_collision \xc3\xa4"};

static void fill_plan_path(robot_plan_path_request_t* req, ln_string_t* strings,
                           robot_plan_path_response_t* resp, robot_joint_state_t* states,
                           uint32_t nstates)
{
    memset(req, 0, sizeof *req);
    for (int i = 0; i < 7; i++)
        req->goal[i] = 0.25 * i - 1;
    req->max_velocity = 1.5;
    for (size_t i = 0; i < LN_ARRAY_SIZE(names); i++) {
        strings[i].data_len = (uint32_t)strlen(names[i]);
        strings[i].data = strings[i].data_len ? (char*)names[i] : NULL;
    }
    req->constraints_len = LN_ARRAY_SIZE(names);
    req->constraints = strings;

    memset(resp, 0, sizeof *resp);
    for (uint32_t k = 0; k < nstates; k++) {
        states[k].timestamp = 0.001 * k;
        states[k].cycle = 1000 + k;
        for (int i = 0; i < 7; i++) {
            states[k].position[i] = k + i / 10.0;
            states[k].velocity[i] = -(double)k * i;
            states[k].effort[i] = 1e-3 * (k ^ (uint32_t)i);
        }
    }
    resp->waypoints_len = nstates;
    resp->waypoints = nstates ? states : NULL;
    resp->status = -42;
    resp->message_len = 7;
    resp->message = "planned";
}

static void test_round_trip_plan_path(void)
{
    ln_sig *sreq, *sresp;
    parse_service(ROBOT_PLAN_PATH_SIGNATURE, &sreq, &sresp);
    if (sreq == NULL || sresp == NULL)
        return;
    robot_plan_path_request_t req, req2;
    robot_plan_path_response_t resp, resp2;
    ln_string_t strings[3];
    robot_joint_state_t states[5];
    fill_plan_path(&req, strings, &resp, states, 5);

    ln_wbuf out;
    ln_wbuf_init(&out);
    ln_arena arena;
    ln_arena_init(&arena, 0);

    LN_CHECK_EQ(encode(sreq, &req, &out), LN_OK);
    size_t names_bytes = 0;
    for (size_t i = 0; i < LN_ARRAY_SIZE(names); i++)
        names_bytes += 4 + strlen(names[i]);
    LN_CHECK_EQ(out.len, 7 * 8 + 8 + 4 + names_bytes);
    LN_CHECK_EQ(ln_sig_decode(sreq, out.data, out.len, &req2, &arena, MAX), LN_OK);
    LN_CHECK(memcmp(req.goal, req2.goal, sizeof req.goal) == 0);
    LN_CHECK(req2.max_velocity == 1.5);
    LN_CHECK_EQ(req2.constraints_len, 3);
    if (req2.constraints_len == 3 && req2.constraints != NULL) {
        for (size_t i = 0; i < 3; i++) {
            LN_CHECK_EQ(req2.constraints[i].data_len, strlen(names[i]));
            if (req2.constraints[i].data_len == 0)
                LN_CHECK(req2.constraints[i].data == NULL);
            else
                LN_CHECK_STREQ(req2.constraints[i].data, names[i]); /* NUL added */
        }
    }

    LN_CHECK_EQ(encode(sresp, &resp, &out), LN_OK);
    LN_CHECK_EQ(out.len, 4 + 5 * 180 + 4 + 4 + 7);
    LN_CHECK_EQ(ln_sig_decode(sresp, out.data, out.len, &resp2, &arena, MAX), LN_OK);
    LN_CHECK_EQ(resp2.waypoints_len, 5);
    LN_CHECK(resp2.waypoints != NULL && resp2.waypoints != states);
    if (resp2.waypoints != NULL) {
        for (uint32_t k = 0; k < 5; k++) {
            LN_CHECK(resp2.waypoints[k].timestamp == states[k].timestamp);
            LN_CHECK_EQ(resp2.waypoints[k].cycle, states[k].cycle);
            LN_CHECK(memcmp(resp2.waypoints[k].position, states[k].position, 56) == 0);
            LN_CHECK(memcmp(resp2.waypoints[k].velocity, states[k].velocity, 56) == 0);
            LN_CHECK(memcmp(resp2.waypoints[k].effort, states[k].effort, 56) == 0);
        }
    }
    LN_CHECK_EQ(resp2.status, -42);
    LN_CHECK_EQ(resp2.message_len, 7);
    LN_CHECK_STREQ(resp2.message, "planned");

    /* No waypoints: count 0 and a NULL pointer. */
    fill_plan_path(&req, strings, &resp, states, 0);
    LN_CHECK_EQ(encode(sresp, &resp, &out), LN_OK);
    LN_CHECK_EQ(ln_sig_decode(sresp, out.data, out.len, &resp2, &arena, MAX), LN_OK);
    LN_CHECK_EQ(resp2.waypoints_len, 0);
    LN_CHECK(resp2.waypoints == NULL);

    /* A count with a NULL pointer cannot be encoded; the buffer is left as it was. */
    ln_wbuf_reset(&out);
    ln_wbuf_u32(&out, 0xabcd);
    strings[2].data = NULL;
    LN_CHECK_EQ(ln_sig_encode(sreq, &req, &out, MAX), LN_EINVAL);
    LN_CHECK(strstr(ln_last_error(), "item 4[2].item 2") != NULL);
    LN_CHECK_EQ(out.len, 4);
    fill_plan_path(&req, strings, &resp, states, 5);
    req.constraints = NULL;
    LN_CHECK_EQ(ln_sig_encode(sreq, &req, &out, MAX), LN_EINVAL);
    LN_CHECK(strstr(ln_last_error(), "item 4:") != NULL);

    ln_arena_free(&arena);
    ln_wbuf_free(&out);
    ln_sig_free(sreq);
    ln_sig_free(sresp);
}

/* ---- lntest/deep: three levels, dynamic fields inside dynamic elements ---- */

static void fill_inner(lntest_inner_t* in, int seed)
{
    in->a = (int16_t)(seed * 3 - 100);
    in->b[0] = seed * 0.5f;
    in->b[1] = -seed * 0.25f;
    memcpy(in->tag, seed % 2 ? "odd!" : "even", 4);
}

static void fill_middle(lntest_middle_t* m, lntest_inner_t* pool, uint32_t ndyn, int seed)
{
    m->flag = (uint8_t)seed;
    fill_inner(&m->one, seed + 1);
    for (int i = 0; i < 3; i++)
        fill_inner(&m->many[i], seed + 2 + i);
    for (uint32_t i = 0; i < ndyn; i++)
        fill_inner(&pool[i], seed + 10 + (int)i);
    m->dyn_len = ndyn;
    m->dyn = ndyn ? pool : NULL;
}

typedef struct deep_data {
    lntest_deep_t d;
    lntest_outer_t os[2];
    lntest_middle_t mids[4][2];
    lntest_inner_t inners[64][3];
    char notes[8][16];
} deep_data;

static void fill_outer(deep_data* x, lntest_outer_t* o, int seed, int* next)
{
    o->t.sec = seed * 1000000007LL;
    o->t.nsec = (uint32_t)seed * 7;
    fill_middle(&o->m, x->inners[(*next)++], (uint32_t)(seed % 3), seed);
    for (int i = 0; i < 2; i++)
        fill_middle(&o->ms[i], x->inners[(*next)++], (uint32_t)(i + 1), seed + 20 + i);
    for (int i = 0; i < 3; i++)
        o->p.position[i] = seed + i;
    for (int i = 0; i < 4; i++)
        o->p.orientation[i] = -seed - i;
    int slot = *next % 4;
    for (int i = 0; i < 2; i++)
        fill_middle(&x->mids[slot][i], x->inners[(*next)++], 2, seed + 40 + i);
    o->ds_len = seed % 2 ? 2 : 0;
    o->ds = o->ds_len ? x->mids[slot] : NULL;
    char* note = x->notes[*next % 8];
    snprintf(note, 16, "note %d", seed);
    o->note_len = (uint32_t)strlen(note);
    o->note = note;
    o->tail = seed / 3.0;
}

static void fill_deep(deep_data* x)
{
    memset(x, 0, sizeof *x);
    int next = 0;
    fill_outer(x, &x->d.o[0], 1, &next);
    fill_outer(x, &x->d.o[1], 2, &next);
    fill_outer(x, &x->os[0], 3, &next);
    fill_outer(x, &x->os[1], 5, &next);
    x->d.os_len = 2;
    x->d.os = x->os;
    fill_inner(&x->d.last, 99);
}

static void test_round_trip_deep(void)
{
    ln_sig* sig = parse(LNTEST_DEEP_SIGNATURE);
    if (sig == NULL)
        return;
    static deep_data x;
    fill_deep(&x);
    ln_wbuf out, again;
    ln_wbuf_init(&out);
    ln_wbuf_init(&again);
    ln_arena arena;
    ln_arena_init(&arena, 256);
    lntest_deep_t d2;
    LN_CHECK_EQ(encode(sig, &x.d, &out), LN_OK);
    LN_CHECK_EQ(ln_sig_decode(sig, out.data, out.len, &d2, &arena, MAX), LN_OK);
    /* Spot checks at every level, then the full comparison by re-encoding. */
    LN_CHECK_EQ(d2.os_len, 2);
    LN_CHECK(d2.os != NULL && d2.os != x.os);
    if (d2.os != NULL) {
        LN_CHECK_EQ(d2.os[1].ds_len, 2);
        LN_CHECK_EQ(d2.os[1].ds[1].dyn_len, 2);
        LN_CHECK_EQ(d2.os[1].ds[1].dyn[1].a, x.os[1].ds[1].dyn[1].a);
        LN_CHECK(memcmp(d2.os[1].ds[1].dyn[1].tag, x.os[1].ds[1].dyn[1].tag, 4) == 0);
        LN_CHECK_STREQ(d2.os[1].note, "note 5");
        LN_CHECK_EQ(d2.os[0].ds_len, 1 * 2);
        LN_CHECK(d2.os[0].ds[0].one.b[1] == x.os[0].ds[0].one.b[1]);
    }
    LN_CHECK_EQ(d2.o[1].ms[1].dyn_len, 2);
    LN_CHECK_EQ(d2.o[1].ms[1].dyn[0].a, x.d.o[1].ms[1].dyn[0].a);
    LN_CHECK_EQ(d2.o[0].ds_len, 2);
    LN_CHECK_EQ(d2.o[1].ds_len, 0);
    LN_CHECK(d2.o[1].ds == NULL);
    LN_CHECK_EQ(d2.o[0].t.sec, 1000000007LL);
    LN_CHECK_EQ(d2.last.a, x.d.last.a);
    LN_CHECK_EQ(encode(sig, &d2, &again), LN_OK);
    LN_CHECK_EQ(again.len, out.len);
    LN_CHECK(again.len == out.len && memcmp(again.data, out.data, out.len) == 0);

    /* Nested NULL pointer: named by its path. */
    x.os[0].ds[1].dyn = NULL;
    LN_CHECK_EQ(ln_sig_encode(sig, &x.d, &again, MAX), LN_EINVAL);
    LN_CHECK(strstr(ln_last_error(), "item 3[0].item 6[1].item 5") != NULL);

    ln_arena_free(&arena);
    ln_wbuf_free(&out);
    ln_wbuf_free(&again);
    ln_sig_free(sig);
}

/* ---- malformed wire data ---- */

static void check_truncations(const ln_sig* sig, const ln_wbuf* good, void* msg)
{
    ln_arena arena;
    ln_arena_init(&arena, 0);
    for (size_t n = 0; n < good->len; n++) {
        /* an exact-size copy, so ASan sees any read past the end */
        uint8_t* copy = malloc(n ? n : 1);
        memcpy(copy, good->data, n);
        int rc = ln_sig_decode(sig, copy, n, msg, &arena, MAX);
        if (rc != LN_EPROTOCOL) {
            ln_test_fail(__FILE__, __LINE__, "truncation gives LN_EPROTOCOL");
            fprintf(stderr, "    %zu of %zu bytes: %d\n", n, good->len, rc);
        }
        free(copy);
        ln_arena_reset(&arena);
    }
    ln_arena_free(&arena);
}

static void test_malformed(void)
{
    ln_sig *sreq, *sresp;
    parse_service(ROBOT_PLAN_PATH_SIGNATURE, &sreq, &sresp);
    ln_sig* sdeep = parse(LNTEST_DEEP_SIGNATURE);
    ln_wbuf out;
    ln_wbuf_init(&out);
    if (sreq == NULL || sresp == NULL || sdeep == NULL)
        goto done;
    robot_plan_path_request_t req;
    robot_plan_path_response_t resp;
    ln_string_t strings[3];
    robot_joint_state_t states[2];
    fill_plan_path(&req, strings, &resp, states, 2);
    static deep_data x;
    fill_deep(&x);
    lntest_deep_t d2;
    ln_arena arena;
    ln_arena_init(&arena, 0);

    LN_CHECK_EQ(encode(sreq, &req, &out), LN_OK);
    check_truncations(sreq, &out, &req);
    LN_CHECK_EQ(ln_sig_decode(sreq, out.data, 66, &req, &arena, MAX), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "item 4: truncated, the element count needs 4 bytes but 2 "
                                     "are left") != NULL);
    LN_CHECK_EQ(ln_sig_decode(sreq, out.data, 80, &req, &arena, MAX), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "item 4[0].item 2: count 12 needs at least 1 bytes per "
                                     "element, only 8 bytes are left") != NULL);
    LN_CHECK_EQ(encode(sresp, &resp, &out), LN_OK);
    check_truncations(sresp, &out, &resp);
    LN_CHECK_EQ(encode(sdeep, &x.d, &out), LN_OK);
    check_truncations(sdeep, &out, &d2);

    /* Trailing bytes. */
    ln_wbuf_u32(&out, 0);
    LN_CHECK_EQ(ln_sig_decode(sdeep, out.data, out.len, &d2, &arena, MAX), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "4 trailing bytes") != NULL);
    ln_arena_reset(&arena);

    /* Hostile counts are refused before anything is allocated. */
    ln_arena_free(&arena);
    ln_arena_init(&arena, 0);
    ln_wbuf_reset(&out);
    ln_wbuf_u32(&out, 0xFFFFFFFFu); /* waypoints */
    ln_wbuf_bytes(&out, states, sizeof states);
    LN_CHECK_EQ(ln_sig_decode(sresp, out.data, out.len, &resp, &arena, MAX), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "item 2: count 4294967295 needs at least 180") != NULL);
    LN_CHECK_EQ(ln_arena_held(&arena), 0);
    ln_wbuf_reset(&out);
    ln_wbuf_bytes(&out, req.goal, 64);
    ln_wbuf_u32(&out, 1);           /* one constraint */
    ln_wbuf_u32(&out, 0xFFFFFFFFu); /* of 4 G chars */
    ln_wbuf_bytes(&out, "abc", 3);
    LN_CHECK_EQ(ln_sig_decode(sreq, out.data, out.len, &req, &arena, MAX), LN_EPROTOCOL);
    LN_CHECK(strstr(ln_last_error(), "item 4[0].item 2: count 4294967295") != NULL);
    LN_CHECK(ln_arena_held(&arena) <= 4096);
    ln_arena_free(&arena);

done:
    ln_wbuf_free(&out);
    ln_sig_free(sreq);
    ln_sig_free(sresp);
    ln_sig_free(sdeep);
}

static void test_limits(void)
{
    ln_sig *sreq, *sresp;
    parse_service(ROBOT_PLAN_PATH_SIGNATURE, &sreq, &sresp);
    if (sreq == NULL || sresp == NULL)
        goto done;
    robot_plan_path_request_t req;
    robot_plan_path_response_t resp;
    ln_string_t strings[3];
    robot_joint_state_t states[4];
    fill_plan_path(&req, strings, &resp, states, 4);
    ln_wbuf out;
    ln_wbuf_init(&out);
    ln_arena arena;
    ln_arena_init(&arena, 0);

    /* Encoding: exactly the size fits, one byte less does not and leaves `out` as it was. */
    LN_CHECK_EQ(encode(sresp, &resp, &out), LN_OK);
    size_t need = out.len;
    ln_wbuf_reset(&out);
    ln_wbuf_u16(&out, 7);
    LN_CHECK_EQ(ln_sig_encode(sresp, &resp, &out, need), LN_OK);
    LN_CHECK_EQ(out.len, 2 + need);
    ln_wbuf_reset(&out);
    LN_CHECK_EQ(ln_sig_encode(sresp, &resp, &out, need - 1), LN_ETOOBIG);
    LN_CHECK_EQ(out.len, 0);
    LN_CHECK(strstr(ln_last_error(), "item 5") != NULL); /* the message is last */
    LN_CHECK_EQ(ln_sig_encode(sresp, &resp, &out, 100), LN_ETOOBIG);
    LN_CHECK(strstr(ln_last_error(), "item 2") != NULL); /* the waypoints */

    /* Decoding: the input itself, and the data allocated for it. */
    LN_CHECK_EQ(encode(sresp, &resp, &out), LN_OK);
    LN_CHECK_EQ(ln_sig_decode(sresp, out.data, out.len, &resp, &arena, out.len - 1), LN_ETOOBIG);
    LN_CHECK_EQ(ln_arena_held(&arena), 0);
    /* 1000 empty strings: 4 wire bytes each but 12 in memory. */
    ln_wbuf_reset(&out);
    ln_wbuf_bytes(&out, req.goal, 64);
    ln_wbuf_u32(&out, 1000);
    for (int i = 0; i < 1000; i++)
        ln_wbuf_u32(&out, 0);
    LN_CHECK_EQ(ln_sig_decode(sreq, out.data, out.len, &req, &arena, out.len), LN_ETOOBIG);
    LN_CHECK(strstr(ln_last_error(), "item 4: 1000 elements would exceed") != NULL);
    LN_CHECK_EQ(ln_sig_decode(sreq, out.data, out.len, &req, &arena, 12000), LN_OK);
    LN_CHECK_EQ(req.constraints_len, 1000);
    LN_CHECK(req.constraints != NULL && req.constraints[999].data_len == 0);

    ln_arena_free(&arena);
    ln_wbuf_free(&out);
done:
    ln_sig_free(sreq);
    ln_sig_free(sresp);
}

static void test_empty_sections(void)
{
    ln_sig *req, *resp;
    parse_service(LNTEST_NOTHING_SIGNATURE, &req, &resp);
    if (req == NULL || resp == NULL)
        goto done;
    ln_wbuf out;
    ln_wbuf_init(&out);
    ln_arena arena;
    ln_arena_init(&arena, 0);
    LN_CHECK_EQ(ln_sig_encode(req, NULL, &out, MAX), LN_OK);
    LN_CHECK_EQ(out.len, 0);
    LN_CHECK_EQ(ln_sig_decode(req, NULL, 0, NULL, &arena, MAX), LN_OK);
    uint8_t one = 0;
    LN_CHECK_EQ(ln_sig_decode(resp, &one, 1, NULL, &arena, MAX), LN_EPROTOCOL);
    ln_wbuf_free(&out);
    ln_arena_free(&arena);
done:
    ln_sig_free(req);
    ln_sig_free(resp);
}

static void test_arena(void)
{
    ln_arena a;
    ln_arena_init(&a, 64);
    void* p1 = ln_arena_alloc(&a, 3);
    void* p2 = ln_arena_alloc(&a, 5);
    LN_CHECK(p1 != NULL && p2 != NULL);
    LN_CHECK_EQ((uintptr_t)p1 % 8, 0);
    LN_CHECK_EQ((uintptr_t)p2 % 8, 0);
    LN_CHECK_EQ((uint8_t*)p2 - (uint8_t*)p1, 8);
    void* big = ln_arena_alloc(&a, 1000); /* its own chunk; the first keeps filling */
    LN_CHECK(big != NULL);
    memset(big, 0xab, 1000);
    void* p3 = ln_arena_alloc(&a, 8);
    LN_CHECK_EQ((uint8_t*)p3 - (uint8_t*)p2, 8);
    LN_CHECK_EQ(ln_arena_held(&a), 64 + 1000);
    LN_CHECK(ln_arena_alloc(&a, SIZE_MAX - 3) == NULL);
    ln_arena_reset(&a);
    LN_CHECK_EQ(ln_arena_held(&a), 64);
    LN_CHECK(ln_arena_alloc(&a, 8) == p1); /* the kept chunk is reused */
    ln_arena_free(&a);
    LN_CHECK_EQ(ln_arena_held(&a), 0);
    ln_arena_free(&a);
}

/* Random byte mutations of valid encodings: never a crash, leak or out-of-bounds read; a
 * mutation that decodes must encode again. */
static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static uint32_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint32_t)(rng_state >> 16);
}

static void fuzz_one(const ln_sig* sig, const ln_wbuf* good, void* msg, int rounds, int* ok)
{
    ln_arena arena;
    ln_arena_init(&arena, 0);
    ln_wbuf again;
    ln_wbuf_init(&again);
    uint8_t* buf = malloc(good->len + 16);
    for (int r = 0; r < rounds; r++) {
        size_t len = good->len;
        memcpy(buf, good->data, len);
        int edits = 1 + (int)(rng() % 4);
        for (int e = 0; e < edits; e++) {
            uint32_t what = rng() % 8, at = len ? rng() % (uint32_t)len : 0;
            if (what < 4 && len > 0)
                buf[at] = (uint8_t)rng();
            else if (what < 6 && len > 0)
                buf[at] ^= (uint8_t)(1u << (rng() % 8));
            else if (what == 6 && len > 0)
                len = at;
            else if (len < good->len + 16)
                buf[len++] = (uint8_t)rng();
        }
        uint8_t* exact = malloc(len ? len : 1);
        memcpy(exact, buf, len);
        int rc = ln_sig_decode(sig, exact, len, msg, &arena, 1 << 20);
        if (rc == LN_OK) {
            ++*ok;
            ln_wbuf_reset(&again);
            LN_CHECK_EQ(ln_sig_encode(sig, msg, &again, 1 << 20), LN_OK);
            LN_CHECK_EQ(again.len, len);
        } else if (rc != LN_EPROTOCOL && rc != LN_ETOOBIG) {
            LN_CHECK_EQ(rc, LN_EPROTOCOL);
        }
        free(exact);
        ln_arena_reset(&arena);
    }
    free(buf);
    ln_wbuf_free(&again);
    ln_arena_free(&arena);
}

static void test_fuzz(void)
{
    ln_sig *sreq, *sresp;
    parse_service(ROBOT_PLAN_PATH_SIGNATURE, &sreq, &sresp);
    ln_sig* sdeep = parse(LNTEST_DEEP_SIGNATURE);
    ln_wbuf out;
    ln_wbuf_init(&out);
    int ok = 0;
    if (sreq == NULL || sresp == NULL || sdeep == NULL)
        goto done;
    robot_plan_path_request_t req;
    robot_plan_path_response_t resp;
    ln_string_t strings[3];
    robot_joint_state_t states[3];
    fill_plan_path(&req, strings, &resp, states, 3);
    static deep_data x;
    fill_deep(&x);
    lntest_deep_t d2;

    LN_CHECK_EQ(encode(sreq, &req, &out), LN_OK);
    fuzz_one(sreq, &out, &req, 7000, &ok);
    LN_CHECK_EQ(encode(sresp, &resp, &out), LN_OK);
    fuzz_one(sresp, &out, &resp, 6000, &ok);
    LN_CHECK_EQ(encode(sdeep, &x.d, &out), LN_OK);
    fuzz_one(sdeep, &out, &d2, 7000, &ok);
    LN_CHECK(ok > 0); /* some mutations only change values */
done:
    ln_wbuf_free(&out);
    ln_sig_free(sreq);
    ln_sig_free(sresp);
    ln_sig_free(sdeep);
}

int main(void)
{
    LN_TEST_RUN(test_parse_generated);
    LN_TEST_RUN(test_bad_signatures);
    LN_TEST_RUN(test_round_trip_plan_path);
    LN_TEST_RUN(test_round_trip_deep);
    LN_TEST_RUN(test_malformed);
    LN_TEST_RUN(test_limits);
    LN_TEST_RUN(test_empty_sections);
    LN_TEST_RUN(test_arena);
    LN_TEST_RUN(test_fuzz);
    LN_TEST_EXIT();
}
