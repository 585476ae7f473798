/* waitset_tool.c — a C waitset driven by the Python waitset tests (tests/python/waiting).
 * The manager comes from $LN_MANAGER; topics carry lntest/pattern samples (topic_tool.c
 * publishes them).  Every event is printed as one line, so the tests see exact sequences.
 *   waitset_tool watch TOPIC DEADLINE_S LIMIT_S   subscribe (queued, 16 buffers), attach with
 *       data + liveliness and the deadline, print "ready", then per event: "data VALUE" (one
 *       line per sample read), "deadline COUNT", "gone", "back"; ends after LIMIT_S seconds
 *       or at a sample whose value is 0 ("end")
 *   waitset_tool timer PERIOD_MS COUNT      an interval timer with an absolute first expiry:
 *       prints "tick COUNT LATE_US" per report, then "done"
 *   waitset_tool many TOPIC N               N subscribers of TOPIC.0 .. TOPIC.N-1 attached,
 *       "ready", then prints "data I VALUE" for each sample until value 0 arrives on one
 *   waitset_tool bad [TOPIC]                bad input: prints "NAME CODE" per check (with
 *       TOPIC and a manager also those that need a real inport)
 *   waitset_tool race SECONDS TOPIC         one thread waits, another attaches and detaches
 *       timers, an inport and triggers for SECONDS (for the sanitizers): prints "ok WAITS" */
#define _POSIX_C_SOURCE 200809L

#include <inttypes.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ln/ln.h>

#include "topic_messages.h"

static int fail(const char* what, int rc)
{
    fprintf(stderr, "waitset_tool: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    return 2;
}

static int64_t mono_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000LL + t.tv_nsec;
}

static int subscribe(ln_client* c, ln_inport** in, const char* topic, uint32_t buffers)
{
    ln_port_options o;
    ln_port_options_init(&o);
    o.buffers = buffers;
    return ln_subscribe(c, in, topic, LNTEST_PATTERN_MD, &o);
}

/* Reads every sample the port has; 1 if one held value 0 (the end mark). */
static int drain(ln_inport* in, const char* prefix)
{
    lntest_pattern_t s;
    int end = 0;
    while (ln_read(in, &s, sizeof s, 0, NULL) == LN_OK) {
        printf("%sdata %" PRIu64 "\n", prefix, s.word[0]);
        end |= s.word[0] == 0;
    }
    return end;
}

static int watch(ln_client* c, const char* topic, double deadline, double limit)
{
    ln_inport* in;
    ln_waitset* ws;
    int rc = subscribe(c, &in, topic, 16);
    if (rc != LN_OK)
        return fail("subscribe", rc);
    if ((rc = ln_waitset_create(&ws)) != LN_OK)
        return fail("create", rc);
    uint32_t id;
    rc = ln_waitset_attach_inport(ws, in, LN_WAIT_ON_DATA | LN_WAIT_ON_LIVELINESS, deadline, NULL,
                                  &id);
    if (rc != LN_OK)
        return fail("attach", rc);
    printf("ready\n");
    fflush(stdout);
    int64_t until = mono_ns() + (int64_t)(limit * 1e9);
    ln_waitset_event ev[8];
    int end = 0;
    while (!end && mono_ns() < until) {
        int n = ln_waitset_wait(ws, (double)(until - mono_ns()) / 1e9, ev, 8);
        if (n < 0 && n != LN_EINTR)
            return fail("wait", n);
        for (int k = 0; k < n; k++) {
            if (ev[k].id != id)
                return fail("an event of another attachment", LN_EPROTOCOL);
            if (ev[k].kind == LN_WAIT_DATA)
                end = drain(in, "");
            else if (ev[k].kind == LN_WAIT_DEADLINE)
                printf("deadline %u\n", ev[k].count);
            else if (ev[k].kind == LN_WAIT_GONE)
                printf("gone\n");
            else if (ev[k].kind == LN_WAIT_BACK)
                printf("back\n");
        }
        fflush(stdout);
    }
    printf("%s\n", end ? "end" : "limit");
    ln_waitset_destroy(ws);
    ln_unsubscribe(in);
    return 0;
}

static int timer(int period_ms, int count)
{
    ln_waitset* ws;
    int rc = ln_waitset_create(&ws);
    if (rc != LN_OK)
        return fail("create", rc);
    int64_t period = (int64_t)period_ms * 1000000;
    int64_t first = mono_ns() + period;
    if ((rc = ln_waitset_attach_timer(ws, first, period_ms / 1e3, NULL, NULL)) != LN_OK)
        return fail("attach_timer", rc);
    int ticks = 0;
    ln_waitset_event ev[4];
    while (ticks < count) {
        int n = ln_waitset_wait(ws, -1, ev, 4);
        if (n < 0)
            return fail("wait", n);
        int64_t now = mono_ns();
        for (int k = 0; k < n; k++) {
            ticks += (int)ev[k].count;
            /* how late this report is behind the absolute schedule of its last expiry */
            int64_t due = first + (int64_t)(ticks - 1) * period;
            printf("tick %u %lld\n", ev[k].count, (long long)((now - due) / 1000));
        }
    }
    printf("done\n");
    return ln_waitset_destroy(ws) == LN_OK ? 0 : 1;
}

static int many(ln_client* c, const char* topic, int n)
{
    ln_inport** in = calloc((size_t)n, sizeof *in);
    ln_waitset* ws;
    int rc = ln_waitset_create(&ws);
    if (rc != LN_OK || in == NULL)
        return fail("create", rc);
    for (intptr_t i = 0; i < n; i++) {
        char name[256];
        snprintf(name, sizeof name, "%s.%d", topic, (int)i);
        if ((rc = subscribe(c, &in[i], name, 4)) != LN_OK)
            return fail("subscribe", rc);
        if ((rc = ln_waitset_attach_inport(ws, in[i], 0, 0, (void*)i, NULL)) != LN_OK)
            return fail("attach", rc);
    }
    printf("ready\n");
    fflush(stdout);
    ln_waitset_event ev[16];
    int end = 0;
    while (!end) {
        int got = ln_waitset_wait(ws, 30, ev, 16);
        if (got <= 0)
            return fail("wait", got == 0 ? LN_ETIMEOUT : got);
        for (int k = 0; k < got; k++) {
            char prefix[32];
            intptr_t i = (intptr_t)ev[k].user_data;
            snprintf(prefix, sizeof prefix, "%d ", (int)i);
            end |= drain(in[i], prefix);
        }
        fflush(stdout);
    }
    printf("end\n");
    ln_waitset_destroy(ws);
    return 0;
}

static void check(const char* name, int rc)
{
    printf("%s %s\n", name, rc == LN_OK ? "OK" : ln_error_name(rc));
}

static int bad(ln_client* c, const char* topic)
{
    ln_waitset* ws;
    ln_waitset_event ev[1];
    check("create_null", ln_waitset_create(NULL));
    int rc = ln_waitset_create(&ws);
    if (rc != LN_OK)
        return fail("create", rc);
    check("wait_null_array", ln_waitset_wait(ws, 0, NULL, 1));
    check("wait_zero_size", ln_waitset_wait(ws, 0, ev, 0));
    check("wait_nan", ln_waitset_wait(ws, 0.0 / 0.0, ev, 1));
    check("wait_negative_poll", ln_waitset_wait(ws, 0, ev, 1) == 0 ? LN_OK : LN_EPROTOCOL);
    check("attach_null_inport", ln_waitset_attach_inport(ws, NULL, 0, 0, NULL, NULL));
    check("attach_bad_fd", ln_waitset_attach_fd(ws, -1, LN_WAIT_READABLE, NULL, NULL));
    check("attach_closed_fd", ln_waitset_attach_fd(ws, 1000, LN_WAIT_READABLE, NULL, NULL));
    check("attach_no_events", ln_waitset_attach_fd(ws, 0, 0, NULL, NULL));
    check("timer_negative", ln_waitset_attach_timer(ws, 0, -1, NULL, NULL));
    check("timer_never", ln_waitset_attach_timer(ws, 0, 0, NULL, NULL));
    check("detach_unknown", ln_waitset_detach(ws, 12345));
    check("deadline_unknown", ln_waitset_set_deadline(ws, 12345, 1));
    check("group_null_client", ln_waitset_attach_service_group(ws, NULL, NULL, NULL, NULL));
    check("provider_null", ln_waitset_attach_provider(ws, NULL, NULL, NULL));
    check("params_null", ln_waitset_attach_parameter_block(ws, NULL, NULL, NULL));
    check("trigger_null", ln_waitset_trigger(NULL));
    if (c != NULL) { /* with a manager: checks that need a real inport */
        ln_inport* in;
        int rc2 = subscribe(c, &in, topic, 1);
        if (rc2 != LN_OK)
            return fail("subscribe", rc2);
        check("attach_negative_deadline", ln_waitset_attach_inport(ws, in, 0, -1, NULL, NULL));
        check("attach_nan_deadline", ln_waitset_attach_inport(ws, in, 0, 0.0 / 0.0, NULL, NULL));
        check("attach_bad_flags", ln_waitset_attach_inport(ws, in, 0x80, 0, NULL, NULL));
        check("attach_inport", ln_waitset_attach_inport(ws, in, 0, 0, NULL, NULL));
        check("attach_inport_twice", ln_waitset_attach_inport(ws, in, 0, 0, NULL, NULL));
        ln_waitset* other;
        ln_waitset_create(&other);
        check("attach_inport_elsewhere", ln_waitset_attach_inport(other, in, 0, 0, NULL, NULL));
        ln_waitset_destroy(other);
        check("group_none", ln_waitset_attach_service_group(ws, c, "no.such.group", NULL, NULL));
        ln_unsubscribe(in); /* detaches it */
    }
    check("destroy", ln_waitset_destroy(ws));
    return 0;
}

struct race {
    ln_waitset* ws;
    ln_inport* in;
    int64_t until;
    int failures;
};

static void* race_thread(void* arg)
{
    struct race* r = arg;
    while (mono_ns() < r->until) {
        uint32_t a, b;
        if (ln_waitset_attach_timer(r->ws, 0, 0.0001, NULL, &a) != LN_OK ||
            ln_waitset_attach_inport(r->ws, r->in, LN_WAIT_ON_DATA | LN_WAIT_ON_LIVELINESS, 0.001,
                                     NULL, &b) != LN_OK)
            r->failures++;
        ln_waitset_trigger(r->ws);
        if (ln_waitset_detach(r->ws, a) != LN_OK || ln_waitset_detach(r->ws, b) != LN_OK)
            r->failures++;
    }
    ln_waitset_trigger(r->ws);
    return NULL;
}

static int race(ln_client* c, double seconds, const char* topic)
{
    struct race r = {.until = mono_ns() + (int64_t)(seconds * 1e9)};
    int rc = ln_waitset_create(&r.ws);
    if (rc == LN_OK)
        rc = subscribe(c, &r.in, topic, 1);
    if (rc != LN_OK)
        return fail("set-up", rc);
    pthread_t t;
    pthread_create(&t, NULL, race_thread, &r);
    long waits = 0;
    ln_waitset_event ev[4];
    while (mono_ns() < r.until) {
        int n = ln_waitset_wait(r.ws, 0.01, ev, 4);
        if (n < 0 && n != LN_EINTR)
            return fail("wait", n);
        for (int k = 0; k < n; k++)
            if (ev[k].kind == LN_WAIT_DATA)
                drain(r.in, "#");
        waits++;
    }
    pthread_join(t, NULL);
    if (r.failures)
        return fail("attach/detach from the other thread", LN_EPROTOCOL);
    printf("ok %ld\n", waits);
    ln_waitset_destroy(r.ws);
    ln_unsubscribe(r.in);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc == 2 && strcmp(argv[1], "bad") == 0)
        return bad(NULL, NULL);
    if (argc == 4 && strcmp(argv[1], "timer") == 0)
        return timer(atoi(argv[2]), atoi(argv[3]));
    ln_client* c;
    int rc = ln_client_create(&c, "waitset_tool", NULL);
    if (rc != LN_OK)
        return fail("client", rc);
    if (argc == 5 && strcmp(argv[1], "watch") == 0)
        rc = watch(c, argv[2], atof(argv[3]), atof(argv[4]));
    else if (argc == 4 && strcmp(argv[1], "many") == 0)
        rc = many(c, argv[2], atoi(argv[3]));
    else if (argc == 3 && strcmp(argv[1], "bad") == 0)
        rc = bad(c, argv[2]);
    else if (argc == 4 && strcmp(argv[1], "race") == 0)
        rc = race(c, atof(argv[2]), argv[3]);
    else {
        fprintf(stderr, "usage: see the top of waitset_tool.c\n");
        rc = 2;
    }
    ln_client_destroy(c);
    return rc;
}
