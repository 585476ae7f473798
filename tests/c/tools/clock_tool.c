/* clock_tool.c — follows the replay clock through the C API (ln_client_use_clock, ln_now),
 * for the Python recording tests.  The manager comes from $LN_MANAGER.
 *   clock_tool TOPIC       ("-": the default topic)
 * Prints "ready" once it follows the clock; then for each line "now" on stdin one line with
 * ln_now's ns, and for "now N" N values read one after the other on one line.  EOF ends it.
 * On failure the error name and text, exit status 1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ln/ln.h>

static int fail(const char* what, int rc)
{
    printf("%s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    return 1;
}

int main(int argc, char** argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: clock_tool TOPIC|-\n");
        return 2;
    }
    ln_client* clnt = NULL;
    int rc = ln_client_create(&clnt, "clock_tool", NULL);
    if (rc != LN_OK)
        return fail("client", rc);
    rc = ln_client_use_clock(clnt, strcmp(argv[1], "-") == 0 ? NULL : argv[1]);
    if (rc != LN_OK)
        return fail("use_clock", rc);
    printf("ready\n");
    fflush(stdout);
    char line[64];
    while (fgets(line, sizeof line, stdin) != NULL) {
        if (strncmp(line, "now", 3) != 0)
            continue;
        long n = strtol(line + 3, NULL, 10);
        if (n < 1)
            n = 1;
        for (long i = 0; i < n; i++) {
            int64_t ns = 0;
            if ((rc = ln_now(clnt, &ns)) != LN_OK)
                return fail("now", rc);
            printf(i + 1 < n ? "%lld " : "%lld\n", (long long)ns);
        }
        fflush(stdout);
    }
    ln_client_destroy(clnt);
    return 0;
}
