/* errors.c — the texts of the error codes of ln/ndn.h, from the one table LN_NDN_ERRNO_MAP. */
#include "ln/ndn.h"

LN_NDN_EXPORT const char* ln_ndn_strerror(int code)
{
    switch (code) {
    case LN_NDN_OK:
        return "success";
#define LN_NDN_TEXT_(name, value, text)                                                            \
    case value:                                                                                    \
        return text;
        LN_NDN_ERRNO_MAP(LN_NDN_TEXT_)
#undef LN_NDN_TEXT_
    default:
        return code > 0 ? "success" : "unknown error";
    }
}
