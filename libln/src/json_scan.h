/* json_scan.h — just enough JSON reading for the manager's CONTROL answers: find a member of
 * the top-level object and read it as a boolean or a string.  No allocation, no tree. */
#ifndef LN_JSON_SCAN_H
#define LN_JSON_SCAN_H

#include <stddef.h>

/* 1 or 0 for a top-level member `key` that is true or false; -1 if it is missing, not a
 * boolean, or `json` is not an object. */
int ln_json_bool(const char* json, const char* key);
/* Copies the string member `key` of the top-level object, unescaped and NUL-terminated
 * (cut at size - 1 bytes), into out[size]: 0, or -1 if it is missing or not a string.
 * \u escapes become UTF-8; a surrogate half becomes '?'. */
int ln_json_string(const char* json, const char* key, char* out, size_t size);

/* Walking an array member (events use it for their handler lists): ln_json_array gives the
 * start of the top-level member `key` if it is an array (else NULL); starting with *pos at
 * that, each ln_json_next gives the text of the next element as (start, len) and returns 1,
 * 0 after the last one, -1 for malformed text.  An element that is an object is read with
 * the functions above after copying it into a NUL-terminated buffer. */
const char* ln_json_array(const char* json, const char* key);
int ln_json_next(const char** pos, const char** start, size_t* len);

/* Writes s as a quoted JSON string into out[size] (NUL-terminated, cut if it does not fit);
 * returns the length the whole quoted string needs (without the NUL), like snprintf. */
size_t ln_json_quote(const char* s, char* out, size_t size);

#endif /* LN_JSON_SCAN_H */
