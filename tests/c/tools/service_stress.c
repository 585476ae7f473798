/* service_stress.c — a C provider and caller of the lntest/echo service, driven by the Python
 * service tests (concurrency, crashes, errors).  The manager comes from $LN_MANAGER.
 *   service_stress provide NAME [pool THREADS | loop] [MAX_SIZE]
 *       serve until stdin closes; prints "ready" once registered.  Handler: text "fail" ->
 *       error response, "silent" -> returns without answering, else sleeps delay_us (printing
 *       "busy" first when delay_us > 0) and echoes.
 *   service_stress call NAME THREADS CALLS TIMEOUT [TEXT_BYTES]
 *       THREADS threads, each with its own handle, make CALLS calls; every response must repeat
 *       its own request.  Prints one JSON line {"ok":N,"mismatch":N,"failed":N,"first_error":S}.
 *   service_stress once NAME TEXT DELAY_US TIMEOUT [REPEAT]
 *       REPEAT calls (default 1) on one handle, each after the first waiting for a line on
 *       stdin, which may give the next call's "TEXT DELAY_US"; prints per call a JSON line
 *       {"rc":"OK"|"E...","error":S,"text":S}. */
#define _GNU_SOURCE
#include <inttypes.h>
#include <sys/select.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <ln/ln.h>

#include "service_messages.h"

#define ECHO LNTEST_ECHO_SERVICE

static ln_client* clnt;

static int fail(const char* what, int rc)
{
    fprintf(stderr, "service_stress: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    return 2;
}

/* JSON string body: quotes, backslashes and control characters escaped. */
static void put_json(const char* s)
{
    putchar('"');
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            printf("\\%c", c);
        else if (c < 0x20)
            printf("\\u%04x", c);
        else
            putchar(c);
    }
    putchar('"');
}

/* ---- provider ---- */

static int handle_echo(ln_client* c, ln_service_request* req, void* user)
{
    (void)c;
    (void)user;
    lntest_echo_request_t in;
    int rc = ln_service_request_get_data(req, &in);
    if (rc != LN_OK)
        return rc;
    if (in.text_len == 4 && memcmp(in.text, "fail", 4) == 0)
        return ln_service_request_respond_error(req, "echo refuses \"fail\"");
    if (in.text_len == 6 && memcmp(in.text, "silent", 6) == 0)
        return 0;
    if (in.delay_us > 0) {
        printf("busy\n");
        fflush(stdout);
        usleep(in.delay_us);
    }
    lntest_echo_response_t out = {in.caller, in.seq, in.text_len, in.text};
    return ln_service_request_respond(req, &out);
}

static int provide(const char* name, const char* mode, const char* threads, size_t max_size)
{
    ln_service_provider* p;
    int rc = ln_get_service_provider(clnt, &p, name, ECHO);
    if (rc == LN_OK)
        rc = ln_service_provider_set_handler(p, handle_echo, NULL);
    if (rc == LN_OK && max_size > 0)
        rc = ln_service_provider_set_max_size(p, max_size);
    if (rc == LN_OK)
        rc = ln_service_provider_register(p, "echo");
    int pool = mode != NULL && strcmp(mode, "pool") == 0;
    if (rc == LN_OK && pool)
        rc = ln_set_max_threads(clnt, "workers", (unsigned)atoi(threads ? threads : "4"));
    if (rc == LN_OK && pool)
        rc = ln_handle_service_group_in_thread_pool(clnt, "echo", "workers");
    if (rc != LN_OK)
        return fail("provide", rc);
    printf("ready\n");
    fflush(stdout);
    if (pool) {
        char buf[64];
        while (fgets(buf, sizeof buf, stdin) != NULL) {
        }
        return 0;
    }
    /* Loop mode: a reader thread would complicate things; poll stdin between waits. */
    for (;;) {
        rc = ln_wait_and_handle_service_group_requests(clnt, "echo", 0.05);
        if (rc < 0 && rc != LN_EINTR)
            return fail("wait_and_handle", rc);
        struct timespec zero = {0, 0};
        fd_set fds;
        FD_ZERO(&fds);
        FD_SET(0, &fds);
        if (pselect(1, &fds, NULL, NULL, &zero, NULL) > 0) {
            char buf[64];
            if (read(0, buf, sizeof buf) <= 0)
                return 0;
        }
    }
}

/* ---- callers ---- */

struct caller {
    pthread_t thread;
    uint32_t index, calls, text_bytes;
    double timeout;
    const char* name;
    uint32_t ok, mismatch, failed;
    int first_rc;
    char first_error[512];
};

static void* caller_thread(void* arg)
{
    struct caller* k = arg;
    ln_service* svc;
    int rc = ln_get_service(clnt, &svc, k->name, ECHO);
    if (rc != LN_OK) {
        k->failed = k->calls;
        k->first_rc = rc;
        snprintf(k->first_error, sizeof k->first_error, "%s", ln_last_error());
        return NULL;
    }
    char* text = malloc(k->text_bytes + 32);
    for (uint32_t i = 0; i < k->calls; i++) {
        int n = snprintf(text, 32, "t%u-c%u-", k->index, i);
        for (uint32_t j = (uint32_t)n; j < k->text_bytes; j++)
            text[j] = (char)('a' + (i + j) % 26);
        uint32_t len = k->text_bytes > (uint32_t)n ? k->text_bytes : (uint32_t)n;
        lntest_echo_request_t req = {k->index, i, 0, len, text};
        lntest_echo_response_t resp;
        rc = ln_service_call(svc, &req, &resp, k->timeout);
        if (rc != LN_OK) {
            if (k->failed++ == 0) {
                k->first_rc = rc;
                snprintf(k->first_error, sizeof k->first_error, "%s", ln_last_error());
            }
        } else if (resp.caller != k->index || resp.seq != i || resp.text_len != len ||
                   memcmp(resp.text, text, len) != 0) {
            k->mismatch++;
        } else {
            k->ok++;
        }
    }
    free(text);
    ln_service_release(svc);
    return NULL;
}

static int call_many(const char* name, int threads, uint32_t calls, double timeout,
                     uint32_t text_bytes)
{
    struct caller* k = calloc((size_t)threads, sizeof *k);
    for (int t = 0; t < threads; t++) {
        k[t] = (struct caller){.index = (uint32_t)t,
                               .calls = calls,
                               .timeout = timeout,
                               .name = name,
                               .text_bytes = text_bytes};
        pthread_create(&k[t].thread, NULL, caller_thread, &k[t]);
    }
    uint64_t ok = 0, mismatch = 0, failed = 0;
    const char* first = "";
    for (int t = 0; t < threads; t++) {
        pthread_join(k[t].thread, NULL);
        ok += k[t].ok;
        mismatch += k[t].mismatch;
        failed += k[t].failed;
        if (first[0] == '\0' && k[t].failed)
            first = k[t].first_error;
    }
    printf("{\"ok\":%" PRIu64 ",\"mismatch\":%" PRIu64 ",\"failed\":%" PRIu64 ",\"first_error\":",
           ok, mismatch, failed);
    put_json(first);
    printf("}\n");
    free(k);
    return ok == (uint64_t)threads * calls ? 0 : 1;
}

static int call_once(const char* name, const char* text, uint32_t delay_us, double timeout,
                     int repeat)
{
    ln_service* svc;
    int rc = ln_get_service(clnt, &svc, name, ECHO);
    if (rc != LN_OK)
        return fail("get_service", rc);
    char next_text[256];
    for (int i = 0; i < repeat; i++) {
        char line[300];
        if (i > 0) {
            if (fgets(line, sizeof line, stdin) == NULL)
                break;
            unsigned d;
            if (sscanf(line, "%255s %u", next_text, &d) == 2) {
                text = next_text;
                delay_us = d;
            }
        }
        lntest_echo_request_t req = {0, (uint32_t)i, delay_us, (uint32_t)strlen(text), (char*)text};
        lntest_echo_response_t resp;
        rc = ln_service_call(svc, &req, &resp, timeout);
        printf("{\"rc\":\"%s\",\"error\":", ln_error_name(rc));
        put_json(rc == LN_OK ? "" : ln_last_error());
        printf(",\"text\":");
        char echoed[4096] = "";
        if (rc == LN_OK)
            snprintf(echoed, sizeof echoed, "%.*s", (int)resp.text_len, resp.text);
        put_json(echoed);
        printf("}\n");
        fflush(stdout);
    }
    ln_service_release(svc);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: see the comment at the top of service_stress.c\n");
        return 2;
    }
    int rc = ln_client_create(&clnt, "service_stress", NULL);
    if (rc != LN_OK)
        return fail("client", rc);
    int status = 2;
    if (strcmp(argv[1], "provide") == 0)
        status = provide(argv[2], argc > 3 ? argv[3] : "loop", argc > 4 ? argv[4] : NULL,
                         argc > 5 ? strtoull(argv[5], NULL, 10) : 0);
    else if (strcmp(argv[1], "call") == 0 && argc >= 6)
        status = call_many(argv[2], atoi(argv[3]), (uint32_t)strtoul(argv[4], NULL, 10),
                           atof(argv[5]), argc > 6 ? (uint32_t)strtoul(argv[6], NULL, 10) : 0);
    else if (strcmp(argv[1], "once") == 0 && argc >= 6)
        status = call_once(argv[2], argv[3], (uint32_t)strtoul(argv[4], NULL, 10), atof(argv[5]),
                           argc > 6 ? atoi(argv[6]) : 1);
    ln_client_destroy(clnt);
    return status;
}
