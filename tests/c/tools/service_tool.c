/* service_tool.c — a C service provider and caller driven by the Python service tests
 * (tests/python/services).  The manager comes from $LN_MANAGER.
 *
 *   service_tool provide NAME [--md MD] [--group G] [--pool N] [--count K]
 *       provide NAME (MD robot/plan_path, the default, or robot/set_gains); prints "ready"
 *       once registered, exits after K handled calls (0, the default: never).  --pool N:
 *       handled by a thread pool of N threads instead of this thread.
 *   service_tool call NAME [--md MD] [--timeout S] [plan_path: --goal G0,..,G6
 *       --max-velocity V --constraint TEXT (repeatable)] [set_gains: --kp K0,..,K6
 *       --kd D0,..,D6 --profile TEXT]
 *       call once, print the response as one line of JSON and exit 0; for an error print
 *       {"error": "ENAME", "text": "..."} and exit 1.
 *
 * robot/plan_path answers one waypoint per constraint i: timestamp i/2, cycle i,
 * position[j] = goal[j] + i, velocity[j] = max_velocity, effort[j] = len(constraint) + j;
 * status = number of constraints, message = the constraints joined by ",".  A constraint
 * "fail" is answered with the error "constraint I is 'fail'".
 * robot/set_gains answers ok = 1 and message = "PROFILE: kp sum S, kd sum S" (%.17g). */
#define _POSIX_C_SOURCE 200809L /* nanosleep */
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ln/ln.h>

#include "service_tool_messages.h"

#define MAX_CONSTRAINTS 64

static atomic_ulong handled;

static int fail(const char* what, int rc)
{
    fprintf(stderr, "service_tool: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
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

/* `v` points into a packed struct (every md layout is), so it may be misaligned for double:
 * each element is copied out instead of dereferenced (UBSan caught that). */
static void json_doubles(const void* v, int n)
{
    putchar('[');
    for (int i = 0; i < n; i++) {
        double d;
        memcpy(&d, (const char*)v + (size_t)i * sizeof d, sizeof d);
        printf("%s%.17g", i ? ", " : "", d);
    }
    putchar(']');
}

/* ---- providers ---- */
static int plan_path_handler(ln_client* clnt, ln_service_request* r, void* user_data)
{
    (void)clnt;
    (void)user_data;
    robot_plan_path_request_t req;
    int rc = ln_service_request_get_data(r, &req);
    if (rc < 0)
        return rc;
    uint32_t n = req.constraints_len;
    size_t text_len = 0;
    for (uint32_t i = 0; i < n; i++) {
        const ln_string_t* c = &req.constraints[i];
        if (c->data_len == 4 && !memcmp(c->data, "fail", 4)) {
            char text[64];
            snprintf(text, sizeof text, "constraint %u is 'fail'", i);
            rc = ln_service_request_respond_error(r, text);
            atomic_fetch_add(&handled, 1);
            return rc < 0 ? rc : 0;
        }
        text_len += c->data_len + 1;
    }
    robot_joint_state_t* waypoints = calloc(n ? n : 1, sizeof *waypoints);
    char* message = malloc(text_len + 1);
    if (!waypoints || !message) {
        free(waypoints);
        free(message);
        return LN_ENOMEM;
    }
    size_t pos = 0;
    for (uint32_t i = 0; i < n; i++) {
        const ln_string_t* c = &req.constraints[i];
        robot_joint_state_t* w = &waypoints[i];
        w->timestamp = i * 0.5;
        w->cycle = i;
        for (int j = 0; j < 7; j++) {
            w->position[j] = req.goal[j] + i;
            w->velocity[j] = req.max_velocity;
            w->effort[j] = (double)c->data_len + j;
        }
        if (i)
            message[pos++] = ',';
        if (c->data_len)
            memcpy(message + pos, c->data, c->data_len);
        pos += c->data_len;
    }
    robot_plan_path_response_t resp = {
        .waypoints_len = n,
        .waypoints = waypoints,
        .status = (int32_t)n,
        .message_len = (uint32_t)pos,
        .message = message,
    };
    rc = ln_service_request_respond(r, &resp);
    free(waypoints);
    free(message);
    atomic_fetch_add(&handled, 1);
    return rc < 0 ? rc : 0;
}

static double sum7(const void* v) /* a packed member, like json_doubles' */
{
    double s = 0;
    for (int j = 0; j < 7; j++) {
        double d;
        memcpy(&d, (const char*)v + (size_t)j * sizeof d, sizeof d);
        s += d;
    }
    return s;
}

static int set_gains_handler(ln_client* clnt, ln_service_request* r, void* user_data)
{
    (void)clnt;
    (void)user_data;
    robot_set_gains_request_t req;
    int rc = ln_service_request_get_data(r, &req);
    if (rc < 0)
        return rc;
    char text[512];
    int len = snprintf(text, sizeof text, "%.*s: kp sum %.17g, kd sum %.17g",
                       (int)(req.profile_name_len > 256 ? 256 : req.profile_name_len),
                       req.profile_name, sum7(req.kp), sum7(req.kd));
    robot_set_gains_response_t resp = {.ok = 1, .message_len = (uint32_t)len, .message = text};
    rc = ln_service_request_respond(r, &resp);
    atomic_fetch_add(&handled, 1);
    return rc < 0 ? rc : 0;
}

static int provide(ln_client* c, const char* name, const char* md, const char* group, unsigned pool,
                   unsigned long count)
{
    ln_service_provider* p;
    ln_service_handler handler;
    int rc;
    if (!strcmp(md, "robot/plan_path")) {
        rc = ln_get_service_provider(c, &p, name, ROBOT_PLAN_PATH_SERVICE);
        handler = plan_path_handler;
    } else if (!strcmp(md, "robot/set_gains")) {
        rc = ln_get_service_provider(c, &p, name, ROBOT_SET_GAINS_SERVICE);
        handler = set_gains_handler;
    } else {
        fprintf(stderr, "service_tool: unknown md %s\n", md);
        return 2;
    }
    if (rc < 0)
        return fail("get_service_provider", rc);
    if ((rc = ln_service_provider_set_handler(p, handler, NULL)) < 0)
        return fail("set_handler", rc);
    if ((rc = ln_service_provider_register(p, group)) < 0)
        return fail("register", rc);
    if (pool) {
        if ((rc = ln_set_max_threads(c, "tool", pool)) < 0)
            return fail("set_max_threads", rc);
        if ((rc = ln_handle_service_group_in_thread_pool(c, group, "tool")) < 0)
            return fail("thread pool", rc);
    }
    printf("ready\n");
    fflush(stdout);
    while (count == 0 || atomic_load(&handled) < count) {
        if (pool) {
            struct timespec ms = {0, 1000000};
            nanosleep(&ms, NULL);
        } else if ((rc = ln_wait_and_handle_service_group_requests(c, group, -1)) < 0 &&
                   rc != LN_EINTR) {
            return fail("wait_and_handle", rc);
        }
    }
    if ((rc = ln_unregister_service_provider(p)) < 0)
        return fail("unregister", rc);
    return 0;
}

/* ---- callers ---- */
static int parse7(const char* text, double* out)
{
    char* end;
    for (int j = 0; j < 7; j++) {
        errno = 0;
        out[j] = strtod(text, &end);
        if (end == text || errno || (j < 6 && *end != ',') || (j == 6 && *end))
            return -1;
        text = end + 1;
    }
    return 0;
}

static int call_error(int rc)
{
    printf("{\"error\": \"%s\", \"text\": ", ln_error_name(rc));
    const char* text = ln_last_error();
    json_string(text, strlen(text));
    printf("}\n");
    return 1;
}

static void print_plan_path(const robot_plan_path_response_t* resp)
{
    printf("{\"status\": %d, \"message\": ", (int)resp->status);
    json_string(resp->message, resp->message_len);
    printf(", \"waypoints\": [");
    for (uint32_t i = 0; i < resp->waypoints_len; i++) {
        const robot_joint_state_t* w = &resp->waypoints[i];
        printf("%s{\"timestamp\": %.17g, \"cycle\": %u, \"position\": ", i ? ", " : "",
               w->timestamp, (unsigned)w->cycle);
        json_doubles(w->position, 7);
        printf(", \"velocity\": ");
        json_doubles(w->velocity, 7);
        printf(", \"effort\": ");
        json_doubles(w->effort, 7);
        putchar('}');
    }
    printf("]}\n");
}

static int call(ln_client* c, const char* name, const char* md, int argc, char** argv)
{
    double timeout = 30, goal[7] = {0}, kp[7] = {0}, kd[7] = {0}, max_velocity = 0;
    ln_string_t constraints[MAX_CONSTRAINTS];
    uint32_t n = 0;
    const char* profile = "";
    if (argc % 2) {
        fprintf(stderr, "service_tool: option %s without a value\n", argv[argc - 1]);
        return 2;
    }
    for (int i = 0; i + 1 < argc; i += 2) {
        const char *opt = argv[i], *val = argv[i + 1];
        int bad = 0;
        if (!strcmp(opt, "--timeout"))
            timeout = atof(val);
        else if (!strcmp(opt, "--goal"))
            bad = parse7(val, goal);
        else if (!strcmp(opt, "--kp"))
            bad = parse7(val, kp);
        else if (!strcmp(opt, "--kd"))
            bad = parse7(val, kd);
        else if (!strcmp(opt, "--max-velocity"))
            max_velocity = atof(val);
        else if (!strcmp(opt, "--profile"))
            profile = val;
        else if (!strcmp(opt, "--constraint") && n < MAX_CONSTRAINTS)
            constraints[n++] = (ln_string_t){(uint32_t)strlen(val), (char*)val};
        else
            bad = 1;
        if (bad) {
            fprintf(stderr, "service_tool: bad option %s %s\n", opt, val);
            return 2;
        }
    }
    ln_service* svc;
    int rc;
    if (!strcmp(md, "robot/plan_path")) {
        if ((rc = ln_get_service(c, &svc, name, ROBOT_PLAN_PATH_SERVICE)) < 0)
            return fail("get_service", rc);
        robot_plan_path_request_t req = {
            .max_velocity = max_velocity, .constraints_len = n, .constraints = constraints};
        memcpy(req.goal, goal, sizeof goal);
        robot_plan_path_response_t resp;
        if ((rc = ln_service_call(svc, &req, &resp, timeout)) < 0)
            return call_error(rc);
        print_plan_path(&resp);
    } else if (!strcmp(md, "robot/set_gains")) {
        if ((rc = ln_get_service(c, &svc, name, ROBOT_SET_GAINS_SERVICE)) < 0)
            return fail("get_service", rc);
        robot_set_gains_request_t req = {.profile_name_len = (uint32_t)strlen(profile),
                                         .profile_name = (char*)profile};
        memcpy(req.kp, kp, sizeof kp);
        memcpy(req.kd, kd, sizeof kd);
        robot_set_gains_response_t resp;
        if ((rc = ln_service_call(svc, &req, &resp, timeout)) < 0)
            return call_error(rc);
        printf("{\"ok\": %u, \"message\": ", (unsigned)resp.ok);
        json_string(resp.message, resp.message_len);
        printf("}\n");
    } else {
        fprintf(stderr, "service_tool: unknown md %s\n", md);
        return 2;
    }
    fflush(stdout);
    if ((rc = ln_service_release(svc)) < 0)
        return fail("release", rc);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: see the top of service_tool.c\n");
        return 2;
    }
    const char *mode = argv[1], *name = argv[2], *md = "robot/plan_path", *group = NULL;
    unsigned pool = 0;
    unsigned long count = 0;
    /* options common to both modes come first; the rest belongs to `call` */
    int rest = 3;
    for (; rest + 1 < argc; rest += 2) {
        if (!strcmp(argv[rest], "--md"))
            md = argv[rest + 1];
        else if (!strcmp(argv[rest], "--group"))
            group = argv[rest + 1];
        else if (!strcmp(argv[rest], "--pool"))
            pool = (unsigned)atoi(argv[rest + 1]);
        else if (!strcmp(argv[rest], "--count"))
            count = strtoul(argv[rest + 1], NULL, 10);
        else
            break;
    }
    ln_client* c;
    int rc = ln_client_create(&c, "service_tool", NULL);
    if (rc < 0)
        return fail("client", rc);
    if (!strcmp(mode, "provide") && rest == argc)
        rc = provide(c, name, md, group, pool, count);
    else if (!strcmp(mode, "call"))
        rc = call(c, name, md, argc - rest, argv + rest);
    else {
        fprintf(stderr, "service_tool: bad arguments\n");
        rc = 2;
    }
    ln_client_destroy(c);
    return rc;
}
