/* ndn_name.c — NDN names as TLV values: taking components off the front, building a name
 * from a URI ("/ln/robot/arm.state/seq=42": "%xx" escapes, "seq=N" SequenceNum components,
 * "T=value" components of type T, "..." for an empty component), appending components and
 * the prefix test.  The opposite direction (name to URI) is in ndn_uri.c. */
#include <string.h>

#include "ndn_internal.h"

LN_NDN_EXPORT int ln_ndn_name_next(ln_ndn_bytes* rest, ln_ndn_component* out)
{
    ln_ndn_i_tlv t;
    int r = ln_ndn_i_next(rest, &t);
    if (r <= 0)
        return r;
    if (t.type == 0 || t.type > 0xffffu)
        return LN_NDN_EMALFORMED;
    out->type = (uint32_t)t.type;
    out->value = t.value;
    return 1;
}

static int hex(char c)
{
    return c >= '0' && c <= '9'   ? c - '0'
           : c >= 'a' && c <= 'f' ? c - 'a' + 10
           : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                  : -1;
}

/* Decimal digits in [s, e) into *v (no sign, no overflow); 0 or LN_NDN_ENAME. */
static int decimal(const char* s, const char* e, uint64_t* v)
{
    uint64_t x = 0;
    if (s == e)
        return LN_NDN_ENAME;
    for (; s < e; s++) {
        /* overflow test without a 64-bit division (none on small cores) */
        if (*s < '0' || *s > '9' || x > 1844674407370955161u ||
            (x == 1844674407370955161u && *s > '5'))
            return LN_NDN_ENAME;
        x = x * 10 + (uint64_t)(*s - '0');
    }
    *v = x;
    return LN_NDN_OK;
}

/* Unescapes [s, e) into out (NULL: only count); the byte count or LN_NDN_ENAME. */
static long unescape(const char* s, const char* e, uint8_t* out)
{
    long n = 0;
    while (s < e) {
        uint8_t b;
        if (*s == '%') {
            if (e - s < 3 || hex(s[1]) < 0 || hex(s[2]) < 0)
                return LN_NDN_ENAME;
            b = (uint8_t)(hex(s[1]) * 16 + hex(s[2]));
            s += 3;
        } else {
            if ((unsigned char)*s <= ' ' || *s == 0x7f)
                return LN_NDN_ENAME;
            b = (uint8_t)*s++;
        }
        if (out)
            out[n] = b;
        n++;
    }
    return n;
}

/* One URI component [s, e) appended to out[cap] at size; the new size or an error. */
static int component_from_uri(uint8_t* out, size_t cap, size_t size, const char* s, const char* e)
{
    const char* eq = s;
    uint64_t type = LN_NDN_T_GENERIC, v;
    long n;
    size_t head;
    int r;
    while (eq < e && *eq != '=')
        eq++;
    if (eq < e) { /* "seq=N" or "T=value" */
        if (eq - s == 3 && memcmp(s, "seq", 3) == 0) {
            if ((r = decimal(eq + 1, e, &v)) < 0)
                return r;
            return ln_ndn_name_append_seq(out, cap, size, v);
        }
        if (decimal(s, eq, &type) == 0) {
            if (type == 0 || type > 0xffffu)
                return LN_NDN_ENAME;
            s = eq + 1;
        } else {
            type = LN_NDN_T_GENERIC; /* '=' inside a generic component */
        }
    }
    for (eq = s; eq < e && *eq == '.'; eq++) {
    }
    if (eq == e && s != e) { /* only periods: three stand for the empty value */
        if (e - s < 3)
            return LN_NDN_ENAME;
        s += 3;
    } else if (s == e) {
        return LN_NDN_ENAME;
    }
    if ((n = unescape(s, e, NULL)) < 0)
        return (int)n;
    if (size > cap || (size_t)n > cap)
        return LN_NDN_ESPACE;
    head = ln_ndn_i_varnum_size((uint32_t)type) + ln_ndn_i_varnum_size((uint32_t)n);
    if (head + (size_t)n > cap - size)
        return LN_NDN_ESPACE;
    size += ln_ndn_i_put_header(out + size, type, (size_t)n);
    unescape(s, e, out + size);
    return (int)(size + (size_t)n);
}

LN_NDN_EXPORT int ln_ndn_name_from_uri(uint8_t* out, size_t cap, const char* uri)
{
    const char* s;
    int size = 0;
    if (!uri || (!out && cap))
        return LN_NDN_EINVAL;
    cap = LN_NDN_I_CLAMP(cap);
    if (strncmp(uri, "ndn:", 4) == 0)
        uri += 4;
    if (*uri != '/')
        return LN_NDN_ENAME;
    s = uri + 1;
    while (*s) {
        const char* e = s;
        while (*e && *e != '/')
            e++;
        if (e == s) /* "//" (a trailing '/' ends the loop before getting here) */
            return LN_NDN_ENAME;
        if ((size = component_from_uri(out, cap, (size_t)size, s, e)) < 0)
            return size;
        s = *e ? e + 1 : e;
    }
    return size;
}

LN_NDN_EXPORT int ln_ndn_name_append(uint8_t* out, size_t cap, size_t size, uint32_t type,
                                     const uint8_t* value, size_t value_size)
{
    size_t need;
    if (type == 0 || type > 0xffffu || (!value && value_size))
        return LN_NDN_ENAME;
    cap = LN_NDN_I_CLAMP(cap);
    if (!out || size > cap)
        return LN_NDN_EINVAL;
    if (value_size > cap)
        return LN_NDN_ESPACE;
    need = ln_ndn_i_tlv_size(type, value_size);
    if (need > cap - size)
        return LN_NDN_ESPACE;
    size += ln_ndn_i_put_header(out + size, type, value_size);
    if (value_size)
        memmove(out + size, value, value_size);
    return (int)(size + value_size);
}

LN_NDN_EXPORT int ln_ndn_name_append_seq(uint8_t* out, size_t cap, size_t size, uint64_t seq)
{
    uint8_t v[8];
    size_t n = ln_ndn_i_put_nonneg(v, seq);
    return ln_ndn_name_append(out, cap, size, LN_NDN_T_SEQUENCE_NUM, v, n);
}

LN_NDN_EXPORT int ln_ndn_name_has_prefix(ln_ndn_bytes name, ln_ndn_bytes prefix)
{
    ln_ndn_bytes rest = prefix;
    ln_ndn_component c;
    int r;
    if (prefix.size > name.size)
        return 0;
    while ((r = ln_ndn_name_next(&rest, &c)) > 0) {
    }
    if (r < 0) /* not a whole number of components */
        return 0;
    return prefix.size == 0 || memcmp(name.data, prefix.data, prefix.size) == 0;
}
