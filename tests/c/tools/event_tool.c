/* event_tool.c — a C event handler and caller of robot/fault_event driven by the Python event
 * tests (tests/python/events).  The manager comes from $LN_MANAGER.
 *
 *   event_tool connect EVENT [--min-severity N] [--group G] [--count K] [--reply]
 *                            [--refuse CODE] [--die CODE] [--name NAME]
 *       connect a handler stating min_severity N (default 0); print "ready" once connected,
 *       then one JSON line per call: {"event", "severity", "code", "text"}; exit after K
 *       calls (0, the default: never).  --reply answers each call with the reply
 *       severity + 1, code * 2, text reversed; --refuse CODE answers the calls with that
 *       code with the error "refused code CODE"; --die CODE kills the process (SIGKILL) when
 *       a call with that code arrives, before answering.  --name: the client's name.
 *   event_tool call EVENT [--severity S] [--code C] [--text T] [--timeout S] [--filter]
 *                         [--md-hash-off]
 *       call once and print {"delivered": N, "results": [{"handler", "client", "code",
 *       "error", "min_severity", "reply": null | {"severity", "code", "text"}}]}, exit 0;
 *       for an error of the call print {"error": "ENAME", "text": "..."} and exit 1.
 *       --filter: only handlers whose min_severity <= S.  --md-hash-off: claim a layout hash
 *       that differs from the md's (to see the layout check). */
#define _POSIX_C_SOURCE 200809L /* kill */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <ln/ln.h>

#include "event_tool_messages.h"

static int fail(const char* what, int rc)
{
    fprintf(stderr, "event_tool: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    return 2;
}

static void json_string(const char* s, size_t n)
{
    putchar('"');
    for (size_t i = 0; i < n; i++) {
        unsigned char ch = (unsigned char)s[i];
        if (ch == '"' || ch == '\\')
            printf("\\%c", ch);
        else if (ch < 0x20)
            printf("\\u%04x", ch);
        else
            putchar(ch);
    }
    putchar('"');
}

static void json_call(const robot_fault_event_call_t* c)
{
    printf("{\"severity\": %u, \"code\": %d, \"text\": ", c->severity, c->code);
    json_string(c->text_len ? c->text : "", c->text_len);
    putchar('}');
}

/* ---- handlers ---- */
typedef struct handler_opts {
    int reply;
    long refuse, die;
    int has_refuse, has_die;
    unsigned long handled;
} handler_opts;

static int on_fault(ln_client* clnt, ln_event_request* call, void* user_data)
{
    (void)clnt;
    handler_opts* o = user_data;
    robot_fault_event_call_t c;
    int rc = ln_event_request_get_data(call, &c);
    if (rc < 0)
        return rc;
    o->handled++;
    if (o->has_die && c.code == o->die)
        kill(getpid(), SIGKILL);
    printf("{\"event\": \"%s\", \"severity\": %u, \"code\": %d, \"text\": ",
           ln_event_request_event_name(call), c.severity, c.code);
    json_string(c.text_len ? c.text : "", c.text_len);
    printf("}\n");
    fflush(stdout);
    if (o->has_refuse && c.code == o->refuse) {
        char text[64];
        snprintf(text, sizeof text, "refused code %d", c.code);
        return ln_event_request_reply_error(call, text);
    }
    if (!o->reply)
        return 0;
    char reversed[4096];
    uint32_t n = c.text_len < sizeof reversed ? c.text_len : (uint32_t)sizeof reversed;
    for (uint32_t i = 0; i < n; i++)
        reversed[i] = c.text[n - 1 - i];
    robot_fault_event_call_t r = {
        .severity = c.severity + 1, .code = c.code * 2, .text_len = n, .text = reversed};
    return ln_event_request_reply(call, &r);
}

static int connect_handler(ln_client* c, const char* event, int argc, char** argv)
{
    robot_fault_event_connect_t conn = {.min_severity = 0};
    handler_opts o = {0};
    const char* group = NULL;
    unsigned long count = 0;
    for (int i = 0; i < argc; i++) {
        const char* opt = argv[i];
        const char* val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(opt, "--reply")) {
            o.reply = 1;
            continue;
        }
        if (val == NULL) {
            fprintf(stderr, "event_tool: %s needs a value\n", opt);
            return 2;
        }
        i++;
        if (!strcmp(opt, "--min-severity"))
            conn.min_severity = (uint32_t)strtoul(val, NULL, 10);
        else if (!strcmp(opt, "--group"))
            group = val;
        else if (!strcmp(opt, "--count"))
            count = strtoul(val, NULL, 10);
        else if (!strcmp(opt, "--refuse"))
            o.has_refuse = 1, o.refuse = strtol(val, NULL, 10);
        else if (!strcmp(opt, "--die"))
            o.has_die = 1, o.die = strtol(val, NULL, 10);
        else if (strcmp(opt, "--name") != 0) {
            fprintf(stderr, "event_tool: unknown option %s\n", opt);
            return 2;
        }
    }
    ln_event_handler* h;
    int rc = ln_event_connect(c, &h, event, ROBOT_FAULT_EVENT_EVENT, &conn, on_fault, &o, group);
    if (rc < 0)
        return fail("connect", rc);
    printf("ready\n");
    fflush(stdout);
    while (count == 0 || o.handled < count) {
        rc = ln_wait_and_handle_service_group_requests(c, group, -1);
        if (rc < 0 && rc != LN_EINTR)
            return fail("wait_and_handle", rc);
    }
    if ((rc = ln_event_disconnect(h)) < 0)
        return fail("disconnect", rc);
    return 0;
}

/* ---- callers ---- */
static int below(const void* connect, void* severity)
{
    const robot_fault_event_connect_t* c = connect;
    return c->min_severity <= *(const uint32_t*)severity;
}

static int call_event(ln_client* c, const char* event, int argc, char** argv)
{
    robot_fault_event_call_t call = {.severity = 0, .code = 0, .text_len = 0, .text = NULL};
    double timeout = -1;
    int filter = 0;
    uint64_t hash = ROBOT_FAULT_EVENT_LAYOUT_HASH;
    for (int i = 0; i < argc; i++) {
        const char* opt = argv[i];
        if (!strcmp(opt, "--filter")) {
            filter = 1;
            continue;
        }
        if (!strcmp(opt, "--md-hash-off")) {
            hash ^= 1;
            continue;
        }
        const char* val = i + 1 < argc ? argv[++i] : NULL;
        if (val == NULL) {
            fprintf(stderr, "event_tool: %s needs a value\n", opt);
            return 2;
        }
        if (!strcmp(opt, "--severity"))
            call.severity = (uint32_t)strtoul(val, NULL, 10);
        else if (!strcmp(opt, "--code"))
            call.code = (int32_t)strtol(val, NULL, 10);
        else if (!strcmp(opt, "--text"))
            call.text = (char*)val, call.text_len = (uint32_t)strlen(val);
        else if (!strcmp(opt, "--timeout"))
            timeout = strtod(val, NULL);
        else {
            fprintf(stderr, "event_tool: unknown option %s\n", opt);
            return 2;
        }
    }
    ln_event* ev;
    int rc =
        ln_get_event(c, &ev, event, ROBOT_FAULT_EVENT_MD_NAME, hash, ROBOT_FAULT_EVENT_SIGNATURE);
    if (rc < 0)
        return fail("get_event", rc);
    uint32_t severity = call.severity;
    if (filter && (rc = ln_event_set_filter(ev, below, &severity)) < 0)
        return fail("set_filter", rc);
    int delivered = ln_event_call(ev, &call, timeout);
    if (delivered < 0) {
        printf("{\"error\": \"%s\", \"text\": ", ln_error_name(delivered));
        const char* text = ln_last_error();
        json_string(text, strlen(text));
        printf("}\n");
        ln_event_release(ev);
        return 1;
    }
    printf("{\"delivered\": %d, \"results\": [", delivered);
    int n = ln_event_result_count(ev);
    for (int i = 0; i < n; i++) {
        ln_event_result r;
        if ((rc = ln_event_get_result(ev, (size_t)i, &r)) < 0)
            return fail("get_result", rc);
        const robot_fault_event_connect_t* conn = r.connect;
        printf("%s{\"handler\": ", i ? ", " : "");
        json_string(r.handler, strlen(r.handler));
        printf(", \"client\": ");
        json_string(r.client, strlen(r.client));
        printf(", \"code\": \"%s\", \"error\": ", ln_error_name(r.code));
        json_string(r.error, strlen(r.error));
        printf(", \"min_severity\": %u, \"reply\": ", conn->min_severity);
        if (r.reply != NULL)
            json_call(r.reply);
        else
            printf("null");
        putchar('}');
    }
    printf("]}\n");
    fflush(stdout);
    if ((rc = ln_event_release(ev)) < 0)
        return fail("release", rc);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: see the top of event_tool.c\n");
        return 2;
    }
    const char *mode = argv[1], *event = argv[2], *name = "event_tool";
    for (int i = 3; i + 1 < argc; i++)
        if (!strcmp(argv[i], "--name"))
            name = argv[i + 1];
    ln_client* c;
    int rc = ln_client_create(&c, name, NULL);
    if (rc < 0)
        return fail("client", rc);
    if (!strcmp(mode, "connect"))
        rc = connect_handler(c, event, argc - 3, argv + 3);
    else if (!strcmp(mode, "call"))
        rc = call_event(c, event, argc - 3, argv + 3);
    else {
        fprintf(stderr, "event_tool: bad mode %s\n", mode);
        rc = 2;
    }
    ln_client_destroy(c);
    return rc;
}
