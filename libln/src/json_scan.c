/* json_scan.c — a skipping scanner over one JSON text: walks the members of the top-level
 * object, skipping nested values by bracket depth (strings with their escapes), to find one
 * member.  Malformed text simply yields "missing". */
#include "json_scan.h"

#include <stdio.h>
#include <string.h>

static const char* skip_ws(const char* p)
{
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')
        p++;
    return p;
}

/* p at an opening quote: returns the position after the closing quote, or NULL. */
static const char* skip_string(const char* p)
{
    for (p++; *p != '\0'; p++) {
        if (*p == '\\') {
            if (*++p == '\0')
                return NULL;
        } else if (*p == '"') {
            return p + 1;
        }
    }
    return NULL;
}

/* p at the start of a value: returns the position after it, or NULL. */
static const char* skip_value(const char* p)
{
    if (*p == '"')
        return skip_string(p);
    if (*p != '{' && *p != '[') {
        while (*p != '\0' && *p != ',' && *p != '}' && *p != ']' && *p != ' ' && *p != '\n')
            p++;
        return p;
    }
    int depth = 0;
    while (*p != '\0') {
        if (*p == '"') {
            p = skip_string(p);
            if (p == NULL)
                return NULL;
            continue;
        }
        if (*p == '{' || *p == '[')
            depth++;
        else if ((*p == '}' || *p == ']') && --depth == 0)
            return p + 1;
        p++;
    }
    return NULL;
}

/* The start of the value of top-level member `key`, or NULL. */
static const char* find_member(const char* json, const char* key)
{
    size_t klen = strlen(key);
    const char* p = skip_ws(json);
    if (*p++ != '{')
        return NULL;
    for (;;) {
        p = skip_ws(p);
        if (*p != '"')
            return NULL;
        const char* name = p + 1;
        const char* end = skip_string(p);
        if (end == NULL)
            return NULL;
        int match = (size_t)(end - 1 - name) == klen && memcmp(name, key, klen) == 0;
        p = skip_ws(end);
        if (*p++ != ':')
            return NULL;
        p = skip_ws(p);
        if (match)
            return p;
        p = skip_value(p);
        if (p == NULL)
            return NULL;
        p = skip_ws(p);
        if (*p++ != ',')
            return NULL;
    }
}

const char* ln_json_array(const char* json, const char* key)
{
    const char* v = find_member(json, key);
    return v != NULL && *v == '[' ? v : NULL;
}

int ln_json_next(const char** pos, const char** start, size_t* len)
{
    const char* p = *pos;
    if (*p == '[') {
        p = skip_ws(p + 1);
        if (*p == ']')
            return 0;
    } else {
        p = skip_ws(p);
        if (*p == ']')
            return 0;
        if (*p != ',')
            return -1;
        p = skip_ws(p + 1);
    }
    const char* end = skip_value(p);
    if (end == NULL || end == p)
        return -1;
    *start = p;
    *len = (size_t)(end - p);
    *pos = end;
    return 1;
}

int ln_json_bool(const char* json, const char* key)
{
    const char* v = find_member(json, key);
    if (v == NULL)
        return -1;
    if (strncmp(v, "true", 4) == 0)
        return 1;
    if (strncmp(v, "false", 5) == 0)
        return 0;
    return -1;
}

static int hex_value(const char* p)
{
    int v = 0;
    for (int i = 0; i < 4; i++) {
        char c = p[i];
        v <<= 4;
        if (c >= '0' && c <= '9')
            v |= c - '0';
        else if (c >= 'a' && c <= 'f')
            v |= c - 'a' + 10;
        else if (c >= 'A' && c <= 'F')
            v |= c - 'A' + 10;
        else
            return -1;
    }
    return v;
}

/* Appends byte c to out[size] at *n, keeping room for the NUL. */
static void put(char* out, size_t size, size_t* n, char c)
{
    if (*n + 1 < size)
        out[(*n)++] = c;
}

int ln_json_string(const char* json, const char* key, char* out, size_t size)
{
    const char* p = find_member(json, key);
    if (p == NULL || *p != '"' || size == 0 || skip_string(p) == NULL)
        return -1;
    size_t n = 0;
    for (p++; *p != '"'; p++) {
        char c = *p;
        if (c == '\\') {
            c = *++p;
            switch (c) {
            case 'n':
                c = '\n';
                break;
            case 't':
                c = '\t';
                break;
            case 'r':
                c = '\r';
                break;
            case 'b':
                c = '\b';
                break;
            case 'f':
                c = '\f';
                break;
            case 'u': {
                int v = hex_value(p + 1);
                if (v < 0)
                    break; /* not an escape after all: the 'u' itself */
                p += 4;
                if (v < 0x80) {
                    c = (char)v;
                } else if (v < 0x800) {
                    put(out, size, &n, (char)(0xC0 | (v >> 6)));
                    c = (char)(0x80 | (v & 0x3F));
                } else if (v >= 0xD800 && v < 0xE000) {
                    c = '?'; /* half of a surrogate pair: not decoded */
                } else {
                    put(out, size, &n, (char)(0xE0 | (v >> 12)));
                    put(out, size, &n, (char)(0x80 | ((v >> 6) & 0x3F)));
                    c = (char)(0x80 | (v & 0x3F));
                }
                break;
            }
            default:
                break; /* \" \\ \/ */
            }
        }
        put(out, size, &n, c);
    }
    out[n] = '\0';
    return 0;
}

size_t ln_json_quote(const char* s, char* out, size_t size)
{
    size_t n = 0;
    char esc[8];
#define PUT(ch)                                                                                    \
    do {                                                                                           \
        if (n + 1 < size)                                                                          \
            out[n] = (ch);                                                                         \
        n++;                                                                                       \
    } while (0)
    PUT('"');
    for (const unsigned char* p = (const unsigned char*)s; *p != '\0'; p++) {
        if (*p == '"' || *p == '\\') {
            PUT('\\');
            PUT((char)*p);
        } else if (*p < 0x20) {
            snprintf(esc, sizeof esc, "\\u%04x", *p);
            for (const char* e = esc; *e != '\0'; e++)
                PUT(*e);
        } else {
            PUT((char)*p);
        }
    }
    PUT('"');
#undef PUT
    if (size > 0)
        out[n < size ? n : size - 1] = '\0';
    return n;
}
