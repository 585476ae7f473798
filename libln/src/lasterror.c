/* lasterror.c — the per-thread last-error text behind ln_last_error(), and the one place
 * where errno values become LN_E* codes.  Every failing libln call records its reason here
 * with context, instead of printing it. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "client_internal.h"

static _Thread_local char last_text[LN_ERROR_TEXT_MAX];

const char* ln_last_error(void) { return last_text; }

int ln_errno_to_code(int err)
{
    switch (err) {
    case ENOMEM:
        return LN_ENOMEM;
    case EACCES:
    case EPERM:
        return LN_EPERM;
    case ETIMEDOUT:
        return LN_ETIMEOUT;
    case ECONNREFUSED:
    case ECONNRESET:
    case ECONNABORTED:
    case EPIPE:
    case ENOTCONN:
    case EHOSTUNREACH:
    case EHOSTDOWN:
    case ENETUNREACH:
    case ENETDOWN:
    case ENETRESET:
        return LN_ECONNECTION;
    case EINTR:
        return LN_EINTR;
    default:
        return LN_ESYS;
    }
}

/* Formats into a local buffer first: the arguments may point into last_text. */
static int record(ln_client* clnt, int code, const char* suffix, const char* fmt, va_list ap)
{
    char text[LN_ERROR_TEXT_MAX];
    int n = vsnprintf(text, sizeof text, fmt, ap);
    if (n < 0)
        snprintf(text, sizeof text, "%s", ln_strerror(code));
    if (suffix != NULL) {
        size_t used = strlen(text);
        snprintf(text + used, sizeof text - used, ": %s", suffix);
    }
    memcpy(last_text, text, sizeof text);
    if (clnt != NULL)
        ln_client_store_error(clnt, code, text);
    return code;
}

int ln_set_error(ln_client* clnt, int code, const char* fmt, ...)
{
    int saved = errno;
    va_list ap;
    va_start(ap, fmt);
    record(clnt, code, NULL, fmt, ap);
    va_end(ap);
    errno = saved;
    return code;
}

int ln_set_errno_error(ln_client* clnt, int err, const char* fmt, ...)
{
    int saved = errno;
    char buf[256];
    const char* reason = strerror_r(err, buf, sizeof buf); /* GNU: returns the text */
    int code = ln_errno_to_code(err);
    va_list ap;
    va_start(ap, fmt);
    record(clnt, code, reason, fmt, ap);
    va_end(ap);
    errno = saved;
    return code;
}
