/* ndn_uri.c — the URI of a name value ("/ln/robot/arm.state/seq=42"), the inverse of
 * ln_ndn_name_from_uri: unreserved characters as they are, other bytes as %XX, SequenceNum
 * components as seq=N, other non-generic types as T=value. */
#include <string.h>

#include "ndn_internal.h"

typedef struct out_buf {
    char* p;
    size_t cap, n;
} out_buf;

static void put(out_buf* o, const char* s, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++, o->n++)
        if (o->n < o->cap)
            o->p[o->n] = s[i];
}

static void put_decimal(out_buf* o, uint64_t v)
{
    char d[20];
    size_t n = 0;
    do {
        d[sizeof d - 1 - n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    put(o, d + sizeof d - n, n);
}

static int unreserved(uint8_t c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
           c == '.' || c == '_' || c == '~';
}

LN_NDN_EXPORT int ln_ndn_name_to_uri(char* out, size_t cap, ln_ndn_bytes name)
{
    static const char digits[] = "0123456789ABCDEF";
    out_buf o;
    ln_ndn_component c;
    uint64_t seq;
    size_t i;
    int r;
    if (!out || cap == 0)
        return LN_NDN_EINVAL;
    o.p = out;
    o.cap = cap;
    o.n = 0;
    while ((r = ln_ndn_name_next(&name, &c)) > 0) {
        put(&o, "/", 1);
        if (c.type == LN_NDN_T_SEQUENCE_NUM && ln_ndn_read_nonneg(c.value, &seq) == 0 &&
            ln_ndn_i_nonneg_size(seq) == c.value.size) {
            put(&o, "seq=", 4);
            put_decimal(&o, seq);
            continue;
        }
        if (c.type != LN_NDN_T_GENERIC) {
            put_decimal(&o, c.type);
            put(&o, "=", 1);
        }
        for (i = 0; i < c.value.size && c.value.data[i] == '.'; i++) {
        }
        if (i == c.value.size) /* empty or only periods: three more periods */
            put(&o, "...", 3);
        for (i = 0; i < c.value.size; i++) {
            uint8_t b = c.value.data[i];
            if (unreserved(b)) {
                put(&o, (const char*)&b, 1);
            } else {
                char e[3];
                e[0] = '%';
                e[1] = digits[b >> 4];
                e[2] = digits[b & 15];
                put(&o, e, 3);
            }
        }
    }
    if (r < 0) {
        out[0] = '\0';
        return r;
    }
    if (o.n == 0)
        put(&o, "/", 1);
    if (o.n >= cap || o.n > 0x7fffffff) {
        out[0] = '\0';
        return LN_NDN_ESPACE;
    }
    out[o.n] = '\0';
    return (int)o.n;
}
