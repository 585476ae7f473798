/* errors.c — the string side of the error table: ln_strerror(), ln_error_name() and
 * ln_error_count(), all expanded from LN_ERRNO_MAP so the table exists exactly once. */
#include "ln_internal.h"

#include <stddef.h>

/* Every code lies in -1 .. -LN_ERROR_COUNT; with the duplicate-case check of the switches
 * below this proves the table is contiguous, which ln_error_count() promises. */
#define LN_ERRNO_RANGE_(name, code, message)                                                       \
    _Static_assert((code) <= -1 && (code) >= -LN_ERROR_COUNT,                                      \
                   "LN_E" #name " must lie in -1 .. -(number of table entries)");
LN_ERRNO_MAP(LN_ERRNO_RANGE_)
#undef LN_ERRNO_RANGE_

const char* ln_strerror(int code)
{
    switch (code) {
    case LN_OK:
        return "success";
#define LN_ERRNO_MESSAGE_(name, value, message)                                                    \
    case LN_##name:                                                                                \
        return message;
        LN_ERRNO_MAP(LN_ERRNO_MESSAGE_)
#undef LN_ERRNO_MESSAGE_
    default:
        return "unknown error";
    }
}

const char* ln_error_name(int code)
{
    switch (code) {
    case LN_OK:
        return "OK";
#define LN_ERRNO_NAME_(name, value, message)                                                       \
    case LN_##name:                                                                                \
        return #name;
        LN_ERRNO_MAP(LN_ERRNO_NAME_)
#undef LN_ERRNO_NAME_
    default:
        return NULL;
    }
}

int ln_error_count(void) { return LN_ERROR_COUNT; }
