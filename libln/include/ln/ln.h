/* ln.h — the public C API of libln, the links_and_nodes client library.
 * This header is the whole contract: everything here is ln_/LN_-prefixed and ABI-stable
 * within one LN_SOVERSION; everything else in libln is internal and not exported. */
#ifndef LN_LN_H
#define LN_LN_H

#ifdef __cplusplus
extern "C" {
#endif

/* Marks a symbol as part of the ABI; libln is built with -fvisibility=hidden. */
#if defined(__GNUC__) || defined(__clang__)
#define LN_EXPORT __attribute__((visibility("default")))
#else
#define LN_EXPORT
#endif

/* ---- versions ----------------------------------------------------------------------------
 * LN_VERSION_* is the release of the API this header describes.  Within one major version a
 * newer minor only adds to the API, so code built against 0.1 runs with a 0.2 library but
 * not the other way round.  LN_SOVERSION is the ELF soname number (libln.so.1). */
#define LN_VERSION_MAJOR 0
#define LN_VERSION_MINOR 1
#define LN_VERSION_PATCH 0
#define LN_SOVERSION 1

#define LN_STRINGIFY_(x) #x
#define LN_STRINGIFY(x) LN_STRINGIFY_(x)
#define LN_VERSION_STRING                                                                     \
    LN_STRINGIFY(LN_VERSION_MAJOR) "." LN_STRINGIFY(LN_VERSION_MINOR) "." LN_STRINGIFY(      \
        LN_VERSION_PATCH)

/* ---- errors ------------------------------------------------------------------------------
 * Every libln function that can fail returns LN_OK (0) or one negative code of this table.
 * The table is written once, here; it expands into enum ln_error, ln_strerror(),
 * ln_error_name() and, through the Python bindings, one exception class per entry.
 * Codes are contiguous from -1 downwards and never change meaning once released; new
 * entries are appended at the end. */
#define LN_ERRNO_MAP(XX)                                                                      \
    XX(EINVAL, -1, "invalid argument")                                                        \
    XX(ENOMEM, -2, "out of memory")                                                           \
    XX(ETIMEOUT, -3, "timed out")                                                             \
    XX(EAGAIN, -4, "operation would block")                                                   \
    XX(ECONNECTION, -5, "manager unreachable or connection lost")                             \
    XX(EPROTOCOL, -6, "malformed protocol frame")                                             \
    XX(EVERSION, -7, "protocol or library version mismatch")                                  \
    XX(ELAYOUT, -8, "message layout hash mismatch")                                           \
    XX(ENOTFOUND, -9, "not found")                                                            \
    XX(EEXIST, -10, "already exists")                                                         \
    XX(ELIMIT, -11, "configured limit reached")                                               \
    XX(ETOOBIG, -12, "data too big")                                                          \
    XX(ECLOSED, -13, "closed")                                                                \
    XX(EBUSY, -14, "resource busy")                                                           \
    XX(EOVERRUN, -15, "reader overrun, messages were lost")                                   \
    XX(ESYS, -16, "system call failed")                                                       \
    XX(EPERM, -17, "permission denied")                                                       \
    XX(EMD, -18, "bad message definition")                                                    \
    XX(ESERVICE, -19, "service provider answered with an error")                              \
    XX(EBADHANDLE, -20, "invalid or destroyed handle")                                        \
    XX(EINTR, -21, "interrupted")

enum ln_error {
    LN_OK = 0,
#define LN_ERRNO_ENUM_(name, code, message) LN_##name = (code),
    LN_ERRNO_MAP(LN_ERRNO_ENUM_)
#undef LN_ERRNO_ENUM_
};

/* Human-readable text for a code: never NULL, "unknown error" for codes not in the table.
 * The string is static; the caller must not free it. */
LN_EXPORT const char* ln_strerror(int code);

/* Table name of a code without the LN_ prefix ("ETIMEOUT"; "OK" for LN_OK), or NULL for a
 * code not in the table.  The string is static. */
LN_EXPORT const char* ln_error_name(int code);

/* Number of error entries in the table (LN_OK not counted).  Their codes are exactly
 * -1 .. -ln_error_count(), which lets bindings enumerate the table at run time. */
LN_EXPORT int ln_error_count(void);

/* Version of the running library as "MAJOR.MINOR.PATCH".  The string is static. */
LN_EXPORT const char* ln_version(void);

/* LN_OK if the running library can serve a caller built against API major.minor (same
 * major, library minor >= minor), LN_EVERSION if not, LN_EINVAL for negative numbers.
 * Call it as LN_VERSION_CHECK() to pass the numbers of the header you compiled against. */
LN_EXPORT int ln_version_check(int major, int minor);
#define LN_VERSION_CHECK() ln_version_check(LN_VERSION_MAJOR, LN_VERSION_MINOR)

#ifdef __cplusplus
}
#endif

#endif /* LN_LN_H */
