/* log_format.h — deferred printf formatting for ln_log (client_log.c): the caller captures
 * the format and its arguments (a copy of each string) into a queue slot, the log sender
 * thread formats them later, so a 1 kHz loop never runs printf's cold code.  Internal. */
#ifndef LN_LOG_FORMAT_H
#define LN_LOG_FORMAT_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#define LN_LOG_MAX_ARGS 16 /* arguments (with `*` widths) a captured format may have */

typedef struct ln_log_arg {
    char kind; /* 'i' signed, 'u' unsigned, 'd' double, 'p' pointer, 's' string, 'c' int */
    union {
        long long i;
        unsigned long long u;
        double d;
        const void* p;
        uint32_t s; /* a string: its offset in the slot's data */
    } v;
} ln_log_arg;

/* Copies `fmt` and the arguments its conversions take from *ap into data[cap] and args:
 * the number of arguments (>= 0), or -1 when the format has what is not captured (%n, %L
 * doubles, %ls, positional arguments, more than LN_LOG_MAX_ARGS, or data too small): then
 * *ap may have been read and the caller formats from a copy it made before. */
int ln_log_capture(char* data, size_t cap, ln_log_arg* args, const char* fmt, va_list* ap);

/* Formats what ln_log_capture took into out[cap] (cut, NUL-terminated); its length. */
size_t ln_log_render(char* out, size_t cap, const char* data, const ln_log_arg* args, int nargs);

#endif /* LN_LOG_FORMAT_H */
