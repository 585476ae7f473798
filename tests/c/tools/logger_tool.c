/* logger_tool.c — drives a topic logger through the C API (ln_logger_*), for the Python
 * logging tests.  The manager comes from $LN_MANAGER.
 *   logger_tool NAME TOPIC DEPTH DIVISOR start        open, add the topic, enable
 *   logger_tool NAME - 0 0 stop PATH                  disable, save PATH on the manager host
 *   logger_tool NAME TOPIC DEPTH DIVISOR add          only add (prints the error if refused)
 * Prints "ok" on success; on failure the error name and text, exit status 1. */
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
    if (argc < 6) {
        fprintf(stderr, "usage: logger_tool NAME TOPIC DEPTH DIVISOR start|add|stop [PATH]\n");
        return 2;
    }
    const char* action = argv[5];
    ln_client* clnt = NULL;
    int rc = ln_client_create(&clnt, "logger_tool", NULL);
    if (rc != LN_OK)
        return fail("client", rc);
    ln_logger* lg = NULL;
    rc = ln_logger_open(clnt, argv[1], &lg);
    if (rc != LN_OK)
        return fail("open", rc);
    if (strcmp(action, "start") == 0 || strcmp(action, "add") == 0) {
        rc = ln_logger_add_topic(lg, argv[2], (uint32_t)strtoul(argv[3], NULL, 10),
                                 (uint32_t)strtoul(argv[4], NULL, 10), 0.0);
        if (rc != LN_OK)
            return fail("add", rc);
        if (strcmp(action, "start") == 0 && (rc = ln_logger_enable(lg)) != LN_OK)
            return fail("enable", rc);
    } else if (strcmp(action, "stop") == 0 && argc == 7) {
        if ((rc = ln_logger_disable(lg)) != LN_OK)
            return fail("disable", rc);
        if ((rc = ln_logger_save(lg, argv[6])) != LN_OK)
            return fail("save", rc);
    } else {
        fprintf(stderr, "logger_tool: unknown action %s\n", action);
        return 2;
    }
    char* answer = NULL;
    rc = ln_control(clnt, "{\"op\": \"logger_list\"}", &answer);
    if (rc != LN_OK)
        return fail("list", rc);
    ln_free(answer);
    ln_logger_close(lg);
    ln_logger_close(NULL); /* harmless */
    ln_client_destroy(clnt);
    printf("ok\n");
    return 0;
}
