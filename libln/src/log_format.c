/* log_format.c — ln_log's deferred formatting (log_format.h): a printf format and its
 * arguments captured by the caller, formatted by the log sender thread one conversion at a
 * time with the C library's own snprintf, so the text is what printf would have made. */
#include "log_format.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/types.h>

/* One conversion after its '%': where its length modifier starts, its length ('H' hh, 'h',
 * 'l', 'q' ll, 'j', 'z', 't', 'L', 0 none), its `*`s and conversion character; the end,
 * or NULL for what is not taken (positional arguments, no conversion character). */
typedef struct spec {
    const char* length_at;
    char length;
    int stars;
    char conv;
} spec;

/* Past a width or precision: `*` (counted: an int argument comes first) or digits. */
static const char* skip_count(spec* s, const char* p)
{
    if (*p == '*') {
        s->stars++;
        return p + 1;
    }
    while (*p >= '0' && *p <= '9')
        p++;
    return p;
}

static const char* parse_spec(const char* p, spec* s)
{
    s->stars = 0;
    s->length = 0;
    if (*p == '%') {
        s->length_at = p;
        s->conv = '%';
        return p + 1;
    }
    while (*p != 0 && strchr("-+ #0'", *p) != NULL)
        p++;
    p = skip_count(s, p); /* width */
    if (*p == '$')
        return NULL;
    if (*p == '.')
        p = skip_count(s, p + 1); /* precision */
    s->length_at = p;
    if (p[0] == 'h' && p[1] == 'h') {
        s->length = 'H';
        p += 2;
    } else if (p[0] == 'l' && p[1] == 'l') {
        s->length = 'q';
        p += 2;
    } else if (*p != 0 && strchr("hljztLq", *p) != NULL) {
        s->length = *p == 'q' ? 'q' : *p;
        p++;
    }
    s->conv = *p;
    return *p == 0 ? NULL : p + 1;
}

static long long signed_arg(char length, va_list* ap)
{
    switch (length) {
    case 'H':
        return (signed char)va_arg(*ap, int);
    case 'h':
        return (short)va_arg(*ap, int);
    case 'l':
        return va_arg(*ap, long);
    case 'q':
        return va_arg(*ap, long long);
    case 'j':
        return (long long)va_arg(*ap, intmax_t);
    case 'z':
        return (long long)va_arg(*ap, ssize_t);
    case 't':
        return (long long)va_arg(*ap, ptrdiff_t);
    default:
        return va_arg(*ap, int);
    }
}

static unsigned long long unsigned_arg(char length, va_list* ap)
{
    switch (length) {
    case 'H':
        return (unsigned char)va_arg(*ap, unsigned);
    case 'h':
        return (unsigned short)va_arg(*ap, unsigned);
    case 'l':
        return va_arg(*ap, unsigned long);
    case 'q':
        return va_arg(*ap, unsigned long long);
    case 'j':
        return (unsigned long long)va_arg(*ap, uintmax_t);
    case 'z':
        return va_arg(*ap, size_t);
    case 't':
        return (unsigned long long)va_arg(*ap, ptrdiff_t);
    default:
        return va_arg(*ap, unsigned);
    }
}

/* One argument of conversion `s` into *a; 0, or -1 if it is not taken. */
static int take(const spec* s, ln_log_arg* a, char* data, size_t cap, size_t* used, va_list* ap)
{
    if (s->length == 'L')
        return -1; /* long double: formatted at once */
    switch (s->conv) {
    case 'd':
    case 'i':
        a->kind = 'i';
        a->v.i = signed_arg(s->length, ap);
        return 0;
    case 'o':
    case 'u':
    case 'x':
    case 'X':
        a->kind = 'u';
        a->v.u = unsigned_arg(s->length, ap);
        return 0;
    case 'c':
        if (s->length != 0)
            return -1;
        a->kind = 'c';
        a->v.i = va_arg(*ap, int);
        return 0;
    case 'f':
    case 'F':
    case 'e':
    case 'E':
    case 'g':
    case 'G':
    case 'a':
    case 'A':
        a->kind = 'd';
        a->v.d = va_arg(*ap, double);
        return 0;
    case 'p':
        a->kind = 'p';
        a->v.p = va_arg(*ap, void*);
        return 0;
    case 's': {
        if (s->length != 0 || *used >= cap)
            return -1;
        const char* str = va_arg(*ap, const char*);
        if (str == NULL)
            str = "(null)";
        size_t n = strnlen(str, cap - *used - 1); /* cut to what the slot holds */
        memcpy(data + *used, str, n);
        data[*used + n] = 0;
        a->kind = 's';
        a->v.s = (uint32_t)*used;
        *used += n + 1;
        return 0;
    }
    default: /* %n, %m, %ls, %lc and the unknown */
        return -1;
    }
}

int ln_log_capture(char* data, size_t cap, ln_log_arg* args, const char* fmt, va_list* ap)
{
    size_t len = strlen(fmt);
    if (len + 1 > cap)
        return -1;
    memcpy(data, fmt, len + 1);
    size_t used = len + 1;
    int n = 0;
    for (const char* p = fmt; *p != 0;) {
        if (*p++ != '%')
            continue;
        spec s;
        if ((p = parse_spec(p, &s)) == NULL)
            return -1;
        if (s.conv == '%')
            continue;
        if (n + s.stars + 1 > LN_LOG_MAX_ARGS)
            return -1;
        for (int i = 0; i < s.stars; i++) {
            args[n].kind = 'c';
            args[n++].v.i = va_arg(*ap, int);
        }
        if (take(&s, &args[n++], data, cap, &used, ap) != 0)
            return -1;
    }
    return n;
}

/* snprintf of one conversion with its `*` values w[0..stars) and its argument. */
static int put(char* out, size_t cap, const char* f, int stars, const int* w, const ln_log_arg* a,
               const char* data)
{
#define LN_PUT(value)                                                                              \
    (stars == 0   ? snprintf(out, cap, f, value)                                                   \
     : stars == 1 ? snprintf(out, cap, f, w[0], value)                                             \
                  : snprintf(out, cap, f, w[0], w[1], value))
    switch (a->kind) {
    case 'i':
        return LN_PUT(a->v.i);
    case 'u':
        return LN_PUT(a->v.u);
    case 'd':
        return LN_PUT(a->v.d);
    case 'p':
        return LN_PUT(a->v.p);
    case 's':
        return LN_PUT(data + a->v.s);
    default:
        return LN_PUT((int)a->v.i);
    }
#undef LN_PUT
}

size_t ln_log_render(char* out, size_t cap, const char* data, const ln_log_arg* args, int nargs)
{
    size_t len = 0;
    int next = 0;
    for (const char* p = data; *p != 0 && len + 1 < cap;) {
        if (*p != '%') {
            out[len++] = *p++;
            continue;
        }
        spec s;
        const char* end = parse_spec(p + 1, &s);
        if (end == NULL || next + s.stars + (s.conv != '%') > nargs)
            break; /* cannot happen for what ln_log_capture took */
        if (s.conv == '%') {
            out[len++] = '%';
            p = end;
            continue;
        }
        char f[40];
        size_t head = (size_t)(s.length_at - p);
        int wide = args[next + s.stars].kind == 'i' || args[next + s.stars].kind == 'u';
        if (head + 4 > sizeof f)
            break;
        memcpy(f, p, head);
        size_t k = head;
        if (wide) {
            f[k++] = 'l';
            f[k++] = 'l';
        }
        f[k++] = s.conv;
        f[k] = 0;
        int w[2] = {0, 0};
        for (int i = 0; i < s.stars; i++)
            w[i] = (int)args[next++].v.i;
        int n = put(out + len, cap - len, f, s.stars, w, &args[next++], data);
        if (n > 0)
            len += (size_t)n < cap - len ? (size_t)n : cap - len - 1;
        p = end;
    }
    out[len] = 0;
    return len;
}
