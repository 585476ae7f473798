/* param_json.c — the JSON reader and writer of parameter blocks (param_json.h): a strict
 * cursor reader (the text comes from whoever calls the block's service) and a growable
 * text buffer that writes values so that they read back exactly. */
#include "param_json.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- reading ---- */

const char* ln_pj_ws(const char* p)
{
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')
        p++;
    return p;
}

char ln_pj_peek(const char** p)
{
    *p = ln_pj_ws(*p);
    return **p;
}

static int hex4(const char* p, unsigned* out)
{
    unsigned v = 0;
    for (int i = 0; i < 4; i++) {
        char c = p[i];
        v <<= 4;
        if (c >= '0' && c <= '9')
            v |= (unsigned)(c - '0');
        else if (c >= 'a' && c <= 'f')
            v |= (unsigned)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F')
            v |= (unsigned)(c - 'A' + 10);
        else
            return -1;
    }
    *out = v;
    return 0;
}

static void put(char* out, size_t cap, size_t* n, char c)
{
    if (*n + 1 < cap)
        out[*n] = c;
    (*n)++;
}

static void put_utf8(char* out, size_t cap, size_t* n, unsigned cp)
{
    if (cp < 0x80) {
        put(out, cap, n, (char)cp);
    } else if (cp < 0x800) {
        put(out, cap, n, (char)(0xC0 | (cp >> 6)));
        put(out, cap, n, (char)(0x80 | (cp & 0x3F)));
    } else if (cp < 0x10000) {
        put(out, cap, n, (char)(0xE0 | (cp >> 12)));
        put(out, cap, n, (char)(0x80 | ((cp >> 6) & 0x3F)));
        put(out, cap, n, (char)(0x80 | (cp & 0x3F)));
    } else {
        put(out, cap, n, (char)(0xF0 | (cp >> 18)));
        put(out, cap, n, (char)(0x80 | ((cp >> 12) & 0x3F)));
        put(out, cap, n, (char)(0x80 | ((cp >> 6) & 0x3F)));
        put(out, cap, n, (char)(0x80 | (cp & 0x3F)));
    }
}

int ln_pj_string(const char** pos, char* out, size_t cap, size_t* len)
{
    const char* p = ln_pj_ws(*pos);
    *pos = p;
    if (*p != '"')
        return -1;
    size_t n = 0;
    for (p++;; p++) {
        unsigned char c = (unsigned char)*p;
        if (c == '"')
            break;
        if (c < 0x20) { /* the end of the text, or a raw control character */
            *pos = p;
            return -1;
        }
        if (c != '\\') {
            put(out, cap, &n, (char)c);
            continue;
        }
        c = (unsigned char)*++p;
        switch (c) {
        case '"':
        case '\\':
        case '/':
            put(out, cap, &n, (char)c);
            break;
        case 'b':
            put(out, cap, &n, '\b');
            break;
        case 'f':
            put(out, cap, &n, '\f');
            break;
        case 'n':
            put(out, cap, &n, '\n');
            break;
        case 'r':
            put(out, cap, &n, '\r');
            break;
        case 't':
            put(out, cap, &n, '\t');
            break;
        case 'u': {
            unsigned cp, low;
            if (hex4(p + 1, &cp) != 0) {
                *pos = p;
                return -1;
            }
            p += 4;
            if (cp >= 0xD800 && cp < 0xDC00 && p[1] == '\\' && p[2] == 'u' &&
                hex4(p + 3, &low) == 0 && low >= 0xDC00 && low < 0xE000) {
                cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
                p += 6;
            } else if (cp >= 0xD800 && cp < 0xE000) {
                cp = 0xFFFD;
            }
            put_utf8(out, cap, &n, cp);
            break;
        }
        default:
            *pos = p;
            return -1;
        }
    }
    if (cap > 0)
        out[n < cap ? n : cap - 1] = '\0';
    if (len != NULL)
        *len = n;
    *pos = p + 1;
    return 0;
}

int ln_pj_number(const char** pos, const char** start, size_t* len)
{
    const char* p = ln_pj_ws(*pos);
    const char* s = p;
    *pos = p;
    if (*p == '-')
        p++;
    if (*p == '0') {
        p++;
    } else if (*p >= '1' && *p <= '9') {
        while (*p >= '0' && *p <= '9')
            p++;
    } else {
        return -1;
    }
    if (*p == '.') {
        p++;
        if (!(*p >= '0' && *p <= '9'))
            return -1;
        while (*p >= '0' && *p <= '9')
            p++;
    }
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-')
            p++;
        if (!(*p >= '0' && *p <= '9'))
            return -1;
        while (*p >= '0' && *p <= '9')
            p++;
    }
    *start = s;
    *len = (size_t)(p - s);
    *pos = p;
    return 0;
}

int ln_pj_bool(const char** pos, int* value)
{
    const char* p = ln_pj_ws(*pos);
    *pos = p;
    if (strncmp(p, "true", 4) == 0) {
        *value = 1;
        *pos = p + 4;
        return 0;
    }
    if (strncmp(p, "false", 5) == 0) {
        *value = 0;
        *pos = p + 5;
        return 0;
    }
    return -1;
}

int ln_pj_open(const char** pos, char bracket)
{
    const char* p = ln_pj_ws(*pos);
    *pos = p;
    if (*p != bracket)
        return -1;
    *pos = p + 1;
    return 0;
}

/* Before the next element of a container closing with `close`: 1 (cursor at it), 0 (end,
 * consumed) or -1. */
static int next(const char** pos, int* first, char close)
{
    const char* p = ln_pj_ws(*pos);
    *pos = p;
    if (*p == close) {
        *pos = p + 1;
        return 0;
    }
    if (!*first) {
        if (*p != ',')
            return -1;
        p = ln_pj_ws(p + 1);
        if (*p == close) { /* a trailing comma */
            *pos = p;
            return -1;
        }
    }
    *first = 0;
    *pos = p;
    return 1;
}

int ln_pj_next_element(const char** pos, int* first) { return next(pos, first, ']'); }

int ln_pj_next_member(const char** pos, int* first, char* key, size_t cap)
{
    int rc = next(pos, first, '}');
    if (rc != 1)
        return rc;
    if (ln_pj_string(pos, key, cap, NULL) != 0)
        return -1;
    const char* p = ln_pj_ws(*pos);
    *pos = p;
    if (*p != ':')
        return -1;
    *pos = ln_pj_ws(p + 1);
    return 1;
}

static int skip(const char** pos, int depth)
{
    if (depth > LN_PJ_MAX_DEPTH)
        return -1;
    char c = ln_pj_peek(pos);
    const char* start;
    size_t len;
    int first = 1, rc, b;
    char scratch[1];
    switch (c) {
    case '"':
        return ln_pj_string(pos, scratch, sizeof scratch, NULL);
    case '{':
        ln_pj_open(pos, '{');
        while ((rc = ln_pj_next_member(pos, &first, scratch, sizeof scratch)) == 1)
            if (skip(pos, depth + 1) != 0)
                return -1;
        return rc;
    case '[':
        ln_pj_open(pos, '[');
        while ((rc = ln_pj_next_element(pos, &first)) == 1)
            if (skip(pos, depth + 1) != 0)
                return -1;
        return rc;
    case 't':
    case 'f':
        return ln_pj_bool(pos, &b);
    case 'n':
        if (strncmp(*pos, "null", 4) != 0)
            return -1;
        *pos += 4;
        return 0;
    default:
        return ln_pj_number(pos, &start, &len);
    }
}

int ln_pj_skip(const char** pos) { return skip(pos, 0); }

/* ---- writing ---- */

void ln_pbuf_init(ln_pbuf* b) { memset(b, 0, sizeof *b); }

void ln_pbuf_free(ln_pbuf* b)
{
    free(b->data);
    ln_pbuf_init(b);
}

static int reserve(ln_pbuf* b, size_t more)
{
    if (b->failed)
        return -1;
    if (b->len + more + 1 <= b->cap)
        return 0;
    size_t cap = b->cap ? b->cap : 256;
    while (cap < b->len + more + 1)
        cap *= 2;
    char* data = realloc(b->data, cap);
    if (data == NULL) {
        b->failed = 1;
        return -1;
    }
    b->data = data;
    b->cap = cap;
    return 0;
}

void ln_pbuf_raw(ln_pbuf* b, const char* text, size_t len)
{
    if (reserve(b, len) != 0)
        return;
    memcpy(b->data + b->len, text, len);
    b->len += len;
    b->data[b->len] = '\0';
}

void ln_pbuf_add(ln_pbuf* b, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || reserve(b, (size_t)n) != 0)
        return;
    va_start(ap, fmt);
    vsnprintf(b->data + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}

/* Length of the UTF-8 sequence at s (at most `left` bytes), 0 if it is not one. */
static size_t utf8_len(const unsigned char* s, size_t left)
{
    size_t n = s[0] >= 0xF0 && s[0] <= 0xF4 ? 4 : s[0] >= 0xE0 ? 3 : s[0] >= 0xC2 ? 2 : 0;
    if (n == 0 || n > left || s[0] >= 0xF5)
        return 0;
    for (size_t i = 1; i < n; i++)
        if ((s[i] & 0xC0) != 0x80)
            return 0;
    unsigned cp = n == 2 ? (s[0] & 0x1Fu) : n == 3 ? (s[0] & 0x0Fu) : (s[0] & 0x07u);
    for (size_t i = 1; i < n; i++)
        cp = (cp << 6) | (s[i] & 0x3Fu);
    if ((n == 3 && (cp < 0x800 || (cp >= 0xD800 && cp < 0xE000))) ||
        (n == 4 && (cp < 0x10000 || cp > 0x10FFFF)))
        return 0;
    return n;
}

void ln_pbuf_quote(ln_pbuf* b, const char* text, size_t len)
{
    const unsigned char* s = (const unsigned char*)text;
    ln_pbuf_raw(b, "\"", 1);
    for (size_t i = 0; i < len;) {
        unsigned char c = s[i];
        if (c == '"' || c == '\\') {
            char esc[2] = {'\\', (char)c};
            ln_pbuf_raw(b, esc, 2);
            i++;
        } else if (c < 0x20 || c == 0x7F) {
            ln_pbuf_add(b, "\\u%04x", c);
            i++;
        } else if (c < 0x80) {
            ln_pbuf_raw(b, (const char*)&s[i], 1);
            i++;
        } else {
            size_t n = utf8_len(&s[i], len - i);
            if (n == 0) {
                ln_pbuf_raw(b, "\\ufffd", 6);
                i++;
            } else {
                ln_pbuf_raw(b, (const char*)&s[i], n);
                i += n;
            }
        }
    }
    ln_pbuf_raw(b, "\"", 1);
}

void ln_pbuf_double(ln_pbuf* b, double v, int single)
{
    if (isnan(v)) {
        ln_pbuf_raw(b, "\"NaN\"", 5);
        return;
    }
    if (isinf(v)) {
        if (v > 0)
            ln_pbuf_raw(b, "\"Infinity\"", 10);
        else
            ln_pbuf_raw(b, "\"-Infinity\"", 11);
        return;
    }
    char text[40];
    for (int digits = single ? 6 : 15; digits <= 17; digits++) {
        snprintf(text, sizeof text, "%.*g", digits, v);
        if (single ? strtof(text, NULL) == (float)v : strtod(text, NULL) == v)
            break;
    }
    /* "1" would read back as an integer: keep a float looking like one */
    if (strpbrk(text, ".eEn") == NULL)
        strcat(text, ".0");
    ln_pbuf_add(b, "%s", text);
}
