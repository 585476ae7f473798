/* param_value.c — the value side of parameter blocks: the md primitive types a parameter may
 * have, reading a JSON value into a parameter's bytes with every check (type, element count,
 * integer range of the type, the parameter's min/max, read-only, the program's validator)
 * and writing a value back as JSON. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "param_internal.h"

static const ln_param_type types[] = {
    {"char", LN_PK_CHAR, 1},     {"int8_t", LN_PK_INT, 1},    {"uint8_t", LN_PK_UINT, 1},
    {"int16_t", LN_PK_INT, 2},   {"uint16_t", LN_PK_UINT, 2}, {"int32_t", LN_PK_INT, 4},
    {"uint32_t", LN_PK_UINT, 4}, {"int64_t", LN_PK_INT, 8},   {"uint64_t", LN_PK_UINT, 8},
    {"float", LN_PK_FLOAT, 4},   {"double", LN_PK_FLOAT, 8},
};

static const struct {
    const char* alias;
    const char* name;
} aliases[] = {
    {"short", "int16_t"}, {"int", "int32_t"}, {"float32_t", "float"}, {"float64_t", "double"}};

const ln_param_type* ln_param_type_find(const char* name)
{
    if (name == NULL)
        return NULL;
    for (size_t i = 0; i < LN_ARRAY_SIZE(aliases); i++)
        if (strcmp(name, aliases[i].alias) == 0)
            name = aliases[i].name;
    for (size_t i = 0; i < LN_ARRAY_SIZE(types); i++)
        if (strcmp(name, types[i].name) == 0)
            return &types[i];
    return NULL;
}

int ln_param_fail(ln_param_err* err, const char* kind, const char* fmt, ...)
{
    err->kind = kind;
    err->code = strcmp(kind, "not_found") == 0   ? LN_ENOTFOUND
                : strcmp(kind, "read_only") == 0 ? LN_EPERM
                                                 : LN_EINVAL;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->reason, sizeof err->reason, fmt, ap);
    va_end(ap);
    for (char* c = err->reason; *c; c++) /* one line, whatever the value held */
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            *c = ' ';
    return -1;
}

/* ---- reading ---- */

static void int_range(const ln_param_type* t, long double* lo, long double* hi)
{
    int bits = (int)t->size * 8;
    if (t->kind == LN_PK_UINT) {
        *lo = 0;
        *hi = ldexpl(1.0L, bits) - 1;
    } else {
        *lo = -ldexpl(1.0L, bits - 1);
        *hi = ldexpl(1.0L, bits - 1) - 1;
    }
}

static void store_int(void* dst, const ln_param_type* t, int64_t s, uint64_t u)
{
    int neg = t->kind == LN_PK_INT;
    switch (t->size) {
    case 1: {
        uint8_t v = neg ? (uint8_t)(int8_t)s : (uint8_t)u;
        memcpy(dst, &v, 1);
        break;
    }
    case 2: {
        uint16_t v = neg ? (uint16_t)(int16_t)s : (uint16_t)u;
        memcpy(dst, &v, 2);
        break;
    }
    case 4: {
        uint32_t v = neg ? (uint32_t)(int32_t)s : (uint32_t)u;
        memcpy(dst, &v, 4);
        break;
    }
    default: {
        uint64_t v = neg ? (uint64_t)s : u;
        memcpy(dst, &v, 8);
        break;
    }
    }
}

/* A signed integer element (1, 2, 4 or 8 bytes, little-endian), sign-extended. */
static int64_t element_int(const ln_param_type* t, const void* src)
{
    switch (t->size) {
    case 1: {
        int8_t x;
        memcpy(&x, src, 1);
        return x;
    }
    case 2: {
        int16_t x;
        memcpy(&x, src, 2);
        return x;
    }
    case 4: {
        int32_t x;
        memcpy(&x, src, 4);
        return x;
    }
    default: {
        int64_t x;
        memcpy(&x, src, 8);
        return x;
    }
    }
}

/* One element as a double, for the range check and for the JSON of the refusal. */
static double element_double(const ln_param_type* t, const void* src)
{
    if (t->kind == LN_PK_FLOAT) {
        if (t->size == 4) {
            float f;
            memcpy(&f, src, 4);
            return f;
        }
        double d;
        memcpy(&d, src, 8);
        return d;
    }
    if (t->kind == LN_PK_UINT) {
        uint64_t v = 0;
        memcpy(&v, src, t->size); /* little-endian: the low bytes */
        return (double)v;
    }
    return (double)element_int(t, src);
}

/* A number for element `where` (e.g. "kp[3]" or "kp") of type t into dst. */
static int parse_number(const ln_param* p, const char** cursor, void* dst, const char* where,
                        ln_param_err* err)
{
    const ln_param_type* t = p->type;
    char c = ln_pj_peek(cursor);
    double special = 0;
    if (c == '"') { /* the names JSON lacks numbers for */
        char word[16];
        size_t len;
        if (ln_pj_string(cursor, word, sizeof word, &len) != 0)
            return ln_param_fail(err, "bad_request", "%s: malformed string", where);
        if (strcmp(word, "NaN") == 0)
            special = NAN;
        else if (strcmp(word, "Infinity") == 0)
            special = INFINITY;
        else if (strcmp(word, "-Infinity") == 0)
            special = -INFINITY;
        if (special == 0 || t->kind != LN_PK_FLOAT)
            return ln_param_fail(err, "type",
                                 "%s: expected a number (%s), not the string "
                                 "\"%.40s\"",
                                 where, t->name, word);
        if (t->size == 4) {
            float f = (float)special;
            memcpy(dst, &f, 4);
        } else {
            memcpy(dst, &special, 8);
        }
        return 0;
    }
    if (c == 't' || c == 'f') { /* a boolean counts as 1/0 for integers (md has no bool) */
        int b;
        if (ln_pj_bool(cursor, &b) != 0)
            return ln_param_fail(err, "bad_request", "%s: malformed value", where);
        if (t->kind == LN_PK_FLOAT)
            return ln_param_fail(err, "type", "%s: expected a number (%s), not %s", where, t->name,
                                 b ? "true" : "false");
        store_int(dst, t, b, (uint64_t)b);
        return 0;
    }
    const char* start;
    size_t len;
    if (ln_pj_number(cursor, &start, &len) != 0) {
        const char* what = c == '['   ? "a list"
                           : c == '{' ? "an object"
                           : c == 'n' ? "null"
                                      : "that";
        if (c != '[' && c != '{' && c != 'n')
            return ln_param_fail(err, "bad_request", "%s: malformed value", where);
        return ln_param_fail(err, "type", "%s: expected a number (%s), not %s", where, t->name,
                             what);
    }
    char text[400];
    if (len >= sizeof text)
        return ln_param_fail(err, "range", "%s: a number of %zu digits", where, len);
    memcpy(text, start, len);
    text[len] = '\0';
    int fraction = strpbrk(text, ".eE") != NULL;
    if (t->kind == LN_PK_FLOAT) {
        errno = 0;
        double d = strtod(text, NULL);
        if (t->size == 4) {
            if (isinf((float)d) || isinf(d))
                return ln_param_fail(err, "range", "%s: %s is out of range for float", where, text);
            float f = (float)d;
            memcpy(dst, &f, 4);
        } else {
            if (isinf(d))
                return ln_param_fail(err, "range", "%s: %s is out of range for double", where,
                                     text);
            memcpy(dst, &d, 8);
        }
        return 0;
    }
    long double lo, hi;
    int_range(t, &lo, &hi);
    if (fraction) { /* 3.0 or 1e3 is a whole number too */
        long double v = strtold(text, NULL);
        if (v != floorl(v))
            return ln_param_fail(err, "type", "%s: expected an integer (%s), not %s", where,
                                 t->name, text);
        if (v < lo || v > hi)
            goto out_of_range;
        if (t->kind == LN_PK_INT)
            store_int(dst, t, (int64_t)v, 0);
        else
            store_int(dst, t, 0, (uint64_t)v);
        return 0;
    }
    errno = 0;
    if (t->kind == LN_PK_INT) {
        long long v = strtoll(text, NULL, 10);
        if (errno == ERANGE || v < lo || v > hi)
            goto out_of_range;
        store_int(dst, t, v, 0);
    } else {
        if (text[0] == '-')
            goto out_of_range;
        unsigned long long v = strtoull(text, NULL, 10);
        if (errno == ERANGE || v > hi)
            goto out_of_range;
        store_int(dst, t, 0, v);
    }
    return 0;
out_of_range:
    return ln_param_fail(err, "range", "%s: %s is out of range for %s (%.0Lf..%.0Lf)", where, text,
                         t->name, lo, hi);
}

/* v as the shortest decimal that reads back as it (as JSON writes it, without quotes). */
static void shortest(double v, int single, char* out, size_t size)
{
    ln_pbuf b;
    ln_pbuf_init(&b);
    ln_pbuf_double(&b, v, single);
    const char* text = b.data != NULL ? b.data : "?";
    size_t len = strlen(text);
    if (len >= 2 && text[0] == '"') { /* NaN, Infinity */
        text++;
        len -= 2;
    }
    if (len > 2 && strcmp(text + len - 2, ".0") == 0) /* a message shows 300, not 300.0 */
        len -= 2;
    snprintf(out, size, "%.*s", (int)len, text);
    ln_pbuf_free(&b);
}

static void range_text(const ln_param* p, char* out, size_t size)
{
    char lo[40] = "-inf", hi[40] = "inf";
    if (p->flags & LN_PARAMETER_MIN)
        shortest(p->min, 0, lo, sizeof lo);
    if (p->flags & LN_PARAMETER_MAX)
        shortest(p->max, 0, hi, sizeof hi);
    snprintf(out, size, "[%s, %s]", lo, hi);
}

static int check_range(const ln_param* p, const void* value, ln_param_err* err)
{
    if (!(p->flags & (LN_PARAMETER_MIN | LN_PARAMETER_MAX)))
        return 0;
    for (uint32_t i = 0; i < p->count; i++) {
        double v = element_double(p->type, (const uint8_t*)value + i * p->type->size);
        int low = (p->flags & LN_PARAMETER_MIN) && !(v >= p->min);
        int high = (p->flags & LN_PARAMETER_MAX) && !(v <= p->max);
        if (low || high) {
            char where[LN_PARAMETER_MAX_NAME + 16], range[96], text[40], bound[40];
            if (p->count > 1)
                snprintf(where, sizeof where, "%s[%u]", p->name, i);
            else
                snprintf(where, sizeof where, "%s", p->name);
            range_text(p, range, sizeof range);
            if (p->type->kind == LN_PK_FLOAT)
                shortest(v, p->type->size == 4, text, sizeof text);
            else
                snprintf(text, sizeof text, "%.0f", v);
            shortest(low ? p->min : p->max, 0, bound, sizeof bound);
            return ln_param_fail(err, "range", "%s: %s is %s the %s %s (allowed: %s)", where, text,
                                 low ? "below" : "above", low ? "minimum" : "maximum", bound,
                                 range);
        }
    }
    return 0;
}

int ln_param_parse(const ln_param* p, const char** cursor, void* dst, ln_param_err* err)
{
    char c = ln_pj_peek(cursor);
    if (c == '\0')
        return ln_param_fail(err, "bad_request", "%s: no value given", p->name);
    if (p->type->kind == LN_PK_CHAR) {
        if (c != '"')
            return ln_param_fail(err, "type", "%s: expected a string (char[%u])", p->name,
                                 p->count);
        char* text = calloc(1, (size_t)p->count + 1);
        size_t len;
        if (text == NULL)
            return ln_param_fail(err, "bad_request", "%s: out of memory", p->name);
        int rc = ln_pj_string(cursor, text, (size_t)p->count + 1, &len);
        if (rc == 0 && len <= p->count)
            memcpy(dst, text, p->count); /* NUL padded */
        free(text);
        if (rc != 0)
            return ln_param_fail(err, "bad_request", "%s: malformed string", p->name);
        if (len > p->count)
            return ln_param_fail(err, "size",
                                 "%s: a string of %zu bytes does not fit in "
                                 "char[%u]",
                                 p->name, len, p->count);
        return 0;
    }
    if (p->count == 1) {
        if (parse_number(p, cursor, dst, p->name, err) != 0)
            return -1;
        return check_range(p, dst, err);
    }
    if (c != '[')
        return ln_param_fail(err, "type", "%s: expected a list of %u values (%s[%u])", p->name,
                             p->count, p->type->name, p->count);
    ln_pj_open(cursor, '[');
    int first = 1, rc;
    uint32_t n = 0;
    while ((rc = ln_pj_next_element(cursor, &first)) == 1) {
        if (n >= p->count) { /* count them all for the message, checking the syntax */
            uint32_t more = n;
            do {
                if (ln_pj_skip(cursor) != 0)
                    return ln_param_fail(err, "bad_request", "%s: malformed list", p->name);
                more++;
            } while ((rc = ln_pj_next_element(cursor, &first)) == 1);
            if (rc != 0)
                return ln_param_fail(err, "bad_request", "%s: malformed list", p->name);
            return ln_param_fail(err, "size", "%s: %u values do not fit in %s[%u]", p->name, more,
                                 p->type->name, p->count);
        }
        char where[LN_PARAMETER_MAX_NAME + 16];
        snprintf(where, sizeof where, "%s[%u]", p->name, n);
        if (parse_number(p, cursor, (uint8_t*)dst + (size_t)n * p->type->size, where, err) != 0)
            return -1;
        n++;
    }
    if (rc != 0)
        return ln_param_fail(err, "bad_request", "%s: malformed list", p->name);
    if (n != p->count)
        return ln_param_fail(err, "size", "%s: expected %u values (%s[%u]), got %u", p->name,
                             p->count, p->type->name, p->count, n);
    return check_range(p, dst, err);
}

int ln_param_check(ln_parameter_block* blk, uint32_t index, const char** cursor, void* dst,
                   ln_param_err* err)
{
    const ln_param* p = &blk->params[index];
    if (p->flags & LN_PARAMETER_READ_ONLY)
        return ln_param_fail(err, "read_only", "%s is read-only", p->name);
    if (ln_param_parse(p, cursor, dst, err) != 0)
        return -1;
    if (blk->validator != NULL) {
        char reason[LN_PARAM_REASON_MAX] = "";
        if (blk->validator(blk, (int)index, p->name, dst, reason, sizeof reason,
                           blk->validator_user) != 0) {
            reason[sizeof reason - 1] = '\0';
            return ln_param_fail(err, "refused", "%s: %s", p->name,
                                 reason[0] ? reason : "refused by the program");
        }
    }
    return 0;
}

/* ---- writing ---- */

static void write_element(ln_pbuf* b, const ln_param_type* t, const void* src)
{
    if (t->kind == LN_PK_FLOAT) {
        ln_pbuf_double(b, element_double(t, src), t->size == 4);
    } else if (t->kind == LN_PK_UINT) {
        uint64_t v = 0;
        memcpy(&v, src, t->size);
        ln_pbuf_add(b, "%" PRIu64, v);
    } else {
        ln_pbuf_add(b, "%" PRId64, element_int(t, src));
    }
}

void ln_param_write(ln_pbuf* b, const ln_param* p, const void* src)
{
    const ln_param_type* t = p->type;
    if (t->kind == LN_PK_CHAR) {
        const char* s = src;
        ln_pbuf_quote(b, s, strnlen(s, p->count));
        return;
    }
    if (p->count == 1) {
        write_element(b, t, src);
        return;
    }
    ln_pbuf_raw(b, "[", 1);
    for (uint32_t i = 0; i < p->count; i++) {
        if (i)
            ln_pbuf_raw(b, ", ", 2);
        write_element(b, t, (const uint8_t*)src + (size_t)i * t->size);
    }
    ln_pbuf_raw(b, "]", 1);
}
