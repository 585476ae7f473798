/* log_tool.c — logs through the C API (ln_log, ln_log_at, LN_LOG), for the Python client
 * logging tests (tests/python/logs).  The manager comes from $LN_MANAGER.
 *   log_tool levels NAME   one line per level, printing "line LEVEL N" for each LN_LOG line
 *   log_tool flood N       N lines in a tight loop, then "done N queued Q dropped D eagain E"
 * Both flush before they end.  On failure the error name and text, exit status 1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ln/ln.h>

static int fail(const char* what, int rc)
{
    printf("%s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    return 1;
}

static int levels(ln_client* clnt)
{
    static const int all[] = {LN_LOG_DEBUG, LN_LOG_INFO, LN_LOG_WARNING, LN_LOG_ERROR,
                              LN_LOG_CRITICAL};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        int line = __LINE__ + 1;
        int rc = LN_LOG(clnt, all[i], "c line at level %d: %s", all[i], "ok");
        if (rc != LN_OK)
            return fail("log", rc);
        printf("line %d %d\n", all[i], line);
    }
    int rc = ln_log(clnt, LN_LOG_INFO, "c line without a place");
    if (rc != LN_OK)
        return fail("log", rc);
    if (ln_log(clnt, 99, "bad level") != LN_EINVAL)
        return fail("bad level accepted", LN_EINVAL);
    return LN_OK;
}

static int flood(ln_client* clnt, long n)
{
    long eagain = 0;
    for (long i = 0; i < n; i++) {
        int rc = ln_log(clnt, LN_LOG_INFO, "flood %ld", i);
        if (rc == LN_EAGAIN)
            eagain++;
        else if (rc != LN_OK)
            return fail("log", rc);
    }
    uint64_t queued = 0, dropped = 0;
    ln_log_counts(clnt, &queued, &dropped);
    printf("done %ld queued %llu dropped %llu eagain %ld\n", n, (unsigned long long)queued,
           (unsigned long long)dropped, eagain);
    return LN_OK;
}

int main(int argc, char** argv)
{
    if (argc != 3 || (strcmp(argv[1], "levels") != 0 && strcmp(argv[1], "flood") != 0)) {
        fprintf(stderr, "usage: log_tool levels NAME | log_tool flood N\n");
        return 2;
    }
    ln_client* clnt = NULL;
    const char* name = strcmp(argv[1], "levels") == 0 ? argv[2] : "log_flood";
    int rc = ln_client_create(&clnt, name, NULL);
    if (rc != LN_OK)
        return fail("client", rc);
    rc = strcmp(argv[1], "levels") == 0 ? levels(clnt) : flood(clnt, strtol(argv[2], NULL, 10));
    if (rc != LN_OK)
        return 1;
    if ((rc = ln_log_flush(clnt, 10.0)) != LN_OK)
        return fail("flush", rc);
    printf("flushed\n");
    fflush(stdout);
    ln_client_destroy(clnt);
    return 0;
}
