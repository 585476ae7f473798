/* svc_ln.c — call round trip of a libln service (bench/echo64: 64 bytes each way) between two
 * processes: the provider echoes the request from its handler, the caller times every
 * ln_service_call.  Manager from $LN_MANAGER. */
#include "bench_common.h"
#include "bench_services.h"

static const char usage[] =
    "usage: svc_ln provide NAME TOTAL                answer TOTAL calls, then exit\n"
    "       svc_ln call NAME COUNT WARMUP OUT        COUNT round trips (ns) to OUT\n";

#define IDLE_LIMIT 60 /* seconds without any call before the provider gives up */

static int echo(ln_client* clnt, ln_service_request* req, void* user_data)
{
    (void)clnt;
    bench_echo64_request_t in;
    bench_echo64_response_t out;
    int rc = ln_service_request_get_data(req, &in);
    if (rc < 0)
        return rc;
    memcpy(out.data, in.data, sizeof out.data);
    if ((rc = ln_service_request_respond(req, &out)) < 0)
        return rc;
    *(uint64_t*)user_data += 1;
    return 0;
}

static int provide(const char* name, uint64_t total)
{
    ln_client* clnt;
    ln_service_provider* provider;
    uint64_t handled = 0;
    int rc = ln_client_create(&clnt, "svc_ln_provider", NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if ((rc = ln_get_service_provider(clnt, &provider, name, BENCH_ECHO64_SERVICE)) < 0)
        bench_fail("ln_get_service_provider", rc);
    if ((rc = ln_service_provider_set_handler(provider, echo, &handled)) < 0)
        bench_fail("ln_service_provider_set_handler", rc);
    if ((rc = ln_service_provider_register(provider, NULL)) < 0)
        bench_fail("ln_service_provider_register", rc);
    bench_ready();
    int idle = 0;
    while (handled < total) {
        if ((rc = ln_wait_and_handle_service_group_requests(clnt, NULL, 1.0)) < 0)
            bench_fail("ln_wait_and_handle_service_group_requests", rc);
        idle = rc == 0 ? idle + 1 : 0;
        if (idle >= IDLE_LIMIT) {
            fprintf(stderr, "svc_ln: no call for %d s after %llu of %llu\n", IDLE_LIMIT,
                    (unsigned long long)handled, (unsigned long long)total);
            return 1;
        }
    }
    if ((rc = ln_unregister_service_provider(provider)) < 0)
        bench_fail("ln_unregister_service_provider", rc);
    ln_client_destroy(clnt);
    return 0;
}

static int call(const char* name, uint64_t count, uint64_t warmup, const char* out)
{
    ln_client* clnt;
    ln_service* svc;
    int rc = ln_client_create(&clnt, "svc_ln_caller", NULL);
    if (rc < 0)
        bench_fail("ln_client_create", rc);
    if ((rc = ln_get_service(clnt, &svc, name, BENCH_ECHO64_SERVICE)) < 0)
        bench_fail("ln_get_service", rc);
    uint64_t* rtt = calloc(count ? count : 1, sizeof(*rtt));
    if (!rtt) {
        fprintf(stderr, "svc_ln: out of memory\n");
        return 2;
    }
    bench_echo64_request_t req;
    bench_echo64_response_t resp;
    memset(&req, 0x5a, sizeof req);
    for (uint64_t i = 0; i < warmup + count; i++) {
        uint64_t t0 = bench_now_ns(), got;
        memcpy(req.data, &i, sizeof i);
        if ((rc = ln_service_call(svc, &req, &resp, 10.0)) < 0)
            bench_fail("ln_service_call", rc);
        uint64_t t1 = bench_now_ns();
        memcpy(&got, resp.data, sizeof got);
        if (got != i) {
            fprintf(stderr, "svc_ln: call %llu came back as %llu\n", (unsigned long long)i,
                    (unsigned long long)got);
            return 1;
        }
        if (i >= warmup)
            rtt[i - warmup] = t1 - t0;
    }
    bench_write_samples(out, rtt, count);
    free(rtt);
    ln_service_release(svc);
    ln_client_destroy(clnt);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc == 4 && strcmp(argv[1], "provide") == 0)
        return provide(argv[2], strtoull(argv[3], NULL, 10));
    if (argc == 6 && strcmp(argv[1], "call") == 0)
        return call(argv[2], strtoull(argv[3], NULL, 10), strtoull(argv[4], NULL, 10), argv[5]);
    fputs(usage, stderr);
    return 2;
}
