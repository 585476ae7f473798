/* ln_internal.h — shared by libln source files and never installed.
 * Includes the public header and the internal API of ln_admin.h, so each source sees exactly
 * the API it implements, and holds the macros that are not part of the contract. */
#ifndef LN_INTERNAL_H
#define LN_INTERNAL_H

#include "ln/ln.h"
#include "ln_admin.h"

/* Number of entries in a true array (not a pointer). */
#define LN_ARRAY_SIZE(a) (sizeof(a) / sizeof((a)[0]))

/* Number of entries in LN_ERRNO_MAP, as a constant expression. */
#define LN_ERRNO_COUNT_(name, code, message) +1
enum { LN_ERROR_COUNT = 0 LN_ERRNO_MAP(LN_ERRNO_COUNT_) };
#undef LN_ERRNO_COUNT_

/* Bytes of an ln_host_id() buffer, NUL included: the manager takes host ids of at most 255. */
#define LN_HOST_ID_MAX 256

#endif /* LN_INTERNAL_H */
