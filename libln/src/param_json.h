/* param_json.h — the JSON that parameter blocks read and write (docs/parameters.md, "Wire"):
 * a cursor reader over NUL-terminated text (objects, arrays, strings, number tokens; depth
 * limited, malformed text is an error, never a crash) and a growable text buffer that
 * writes JSON.  Internal to libln; used on the service thread only, never by update(). */
#ifndef LN_PARAM_JSON_H
#define LN_PARAM_JSON_H

#include <stddef.h>
#include <stdint.h>

#define LN_PJ_MAX_DEPTH 64

/* ---- reading ----
 * Every function takes the cursor *p at the start of what it reads (blanks before it are
 * skipped) and moves it past what it read; on malformed text it returns -1 and leaves *p
 * where the problem is. */
const char* ln_pj_ws(const char* p);
/* Skips one value of any kind.  0 or -1. */
int ln_pj_skip(const char** p);
/* A string value, unescaped into out[cap] (NUL-terminated; *len is its length without the
 * NUL, which may be more than cap - 1: then it was cut).  \u escapes become UTF-8 (a lone
 * surrogate half becomes U+FFFD).  0 or -1 (also when the value is not a string). */
int ln_pj_string(const char** p, char* out, size_t cap, size_t* len);
/* A number token: *start and *len give its text, checked against JSON's number grammar.  0, or -1
 * when the value is not a number. */
int ln_pj_number(const char** p, const char** start, size_t* len);
/* true/false: 1 or 0 into *value.  0, or -1 when the value is not a boolean. */
int ln_pj_bool(const char** p, int* value);
/* The kind of the value at *p: one of "{[\"tfn" or a digit/'-' for a number, 0 at the end
 * of the text.  Does not move the cursor past the value (only past blanks). */
char ln_pj_peek(const char** p);
/* Containers: *first must be 1 before the first call.  1 when there is a next element (the
 * cursor at its value; for objects the key unescaped into key[cap]), 0 at the end (the
 * closing bracket consumed), -1 when malformed.  The caller reads or skips each value
 * before asking for the next.  Opening: ln_pj_open consumes '{' or '[' (-1 if the value is
 * not that container). */
int ln_pj_open(const char** p, char bracket);
int ln_pj_next_member(const char** p, int* first, char* key, size_t cap);
int ln_pj_next_element(const char** p, int* first);

/* ---- writing ---- */
typedef struct ln_pbuf {
    char* data; /* NUL-terminated while not failed */
    size_t len, cap;
    int failed; /* out of memory: everything after is dropped */
} ln_pbuf;

void ln_pbuf_init(ln_pbuf* b);
void ln_pbuf_free(ln_pbuf* b);
void ln_pbuf_add(ln_pbuf* b, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
void ln_pbuf_raw(ln_pbuf* b, const char* text, size_t len);
/* text[len] as a quoted JSON string (control characters and quotes escaped; bytes that are
 * not UTF-8 become U+FFFD). */
void ln_pbuf_quote(ln_pbuf* b, const char* text, size_t len);
/* A double as the shortest decimal that reads back as the same double (as the float it
 * came from with `single`); NaN and the infinities as the strings "NaN", "Infinity",
 * "-Infinity" (JSON has no such numbers). */
void ln_pbuf_double(ln_pbuf* b, double v, int single);

#endif /* LN_PARAM_JSON_H */
