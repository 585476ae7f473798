/* logger.c — ln_logger_*: a handle naming one of the manager's topic loggers; each call is
 * one control command (docs/logging.md, "Control commands"). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client_internal.h"
#include "json_scan.h"

#define LN_LOGGER_MAGIC 0x4c4e4c47u

struct ln_logger {
    uint32_t magic;
    ln_client* clnt;
    char* quoted_name; /* the name as a JSON string */
};

static int bad_logger(const ln_logger* lg, const char* what)
{
    if (lg == NULL || lg->magic != LN_LOGGER_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "%s: invalid or closed logger handle", what);
    return LN_OK;
}

/* Quotes s as a JSON string into a new buffer (NULL: out of memory). */
static char* quote(const char* s)
{
    size_t n = ln_json_quote(s, NULL, 0);
    char* out = malloc(n + 1);
    if (out != NULL)
        ln_json_quote(s, out, n + 1);
    return out;
}

/* Sends {"op": OP, "name": NAME<, extra>}; `extra` is printf-formatted JSON members. */
static int command(ln_logger* lg, const char* op, const char* extra_fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int command(ln_logger* lg, const char* op, const char* extra_fmt, ...)
{
    char extra[4096] = "";
    if (extra_fmt != NULL) {
        va_list ap;
        va_start(ap, extra_fmt);
        int n = vsnprintf(extra, sizeof extra, extra_fmt, ap);
        va_end(ap);
        if (n < 0 || (size_t)n >= sizeof extra)
            return ln_set_error(lg->clnt, LN_ETOOBIG, "logger %s: arguments too long", op);
    }
    size_t size = strlen(op) + strlen(lg->quoted_name) + strlen(extra) + 40;
    char* text = malloc(size);
    if (text == NULL)
        return ln_set_error(lg->clnt, LN_ENOMEM, "out of memory");
    snprintf(text, size, "{\"op\": \"%s\", \"name\": %s%s%s}", op, lg->quoted_name,
             extra[0] != '\0' ? ", " : "", extra);
    int rc = ln_control(lg->clnt, text, NULL);
    free(text);
    return rc;
}

int ln_logger_open(ln_client* clnt, const char* name, ln_logger** out)
{
    if (out == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_logger_open: out is NULL");
    *out = NULL;
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (name == NULL || name[0] == '\0')
        return ln_set_error(clnt, LN_EINVAL, "ln_logger_open: a logger needs a name");
    ln_logger* lg = calloc(1, sizeof *lg);
    if (lg == NULL || (lg->quoted_name = quote(name)) == NULL) {
        free(lg);
        return ln_set_error(clnt, LN_ENOMEM, "out of memory");
    }
    lg->magic = LN_LOGGER_MAGIC;
    lg->clnt = clnt;
    rc = command(lg, "logger_open", NULL);
    if (rc != LN_OK) {
        ln_logger_close(lg);
        return rc;
    }
    *out = lg;
    return LN_OK;
}

int ln_logger_add_topic(ln_logger* lg, const char* topic, uint32_t depth, uint32_t divisor,
                        double span)
{
    int rc = bad_logger(lg, "ln_logger_add_topic");
    if (rc != LN_OK)
        return rc;
    if (topic == NULL || depth == 0 || divisor == 0 || !(span >= 0) || isinf(span))
        return ln_set_error(lg->clnt, LN_EINVAL,
                            "ln_logger_add_topic: needs a topic, depth "
                            ">= 1, divisor >= 1 and a finite span >= 0");
    char* quoted = quote(topic);
    if (quoted == NULL)
        return ln_set_error(lg->clnt, LN_ENOMEM, "out of memory");
    rc = command(lg, "logger_add",
                 "\"topic\": %s, \"depth\": %u, \"divisor\": %u, "
                 "\"span\": %.17g",
                 quoted, depth, divisor, span);
    free(quoted);
    return rc;
}

int ln_logger_enable(ln_logger* lg)
{
    int rc = bad_logger(lg, "ln_logger_enable");
    return rc != LN_OK ? rc : command(lg, "logger_enable", NULL);
}

int ln_logger_disable(ln_logger* lg)
{
    int rc = bad_logger(lg, "ln_logger_disable");
    return rc != LN_OK ? rc : command(lg, "logger_disable", NULL);
}

int ln_logger_save(ln_logger* lg, const char* path)
{
    int rc = bad_logger(lg, "ln_logger_save");
    if (rc != LN_OK)
        return rc;
    if (path == NULL || path[0] == '\0')
        return ln_set_error(lg->clnt, LN_EINVAL, "ln_logger_save: a file name is required");
    char* quoted = quote(path);
    if (quoted == NULL)
        return ln_set_error(lg->clnt, LN_ENOMEM, "out of memory");
    rc = command(lg, "logger_save", "\"path\": %s", quoted);
    free(quoted);
    return rc;
}

void ln_logger_close(ln_logger* lg)
{
    if (lg == NULL || lg->magic != LN_LOGGER_MAGIC)
        return;
    lg->magic = 0;
    free(lg->quoted_name);
    free(lg);
}
