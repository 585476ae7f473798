/* version.c — run-time view of the version macros in ln.h, so a program can tell which
 * libln it was loaded with and whether that library can serve the header it was built with. */
#include "ln_internal.h"

const char* ln_version(void) { return LN_VERSION_STRING; }

int ln_version_check(int major, int minor)
{
    if (major < 0 || minor < 0)
        return LN_EINVAL;
    /* A minor release only adds API, so an older caller is served by a newer library. */
    if (major != LN_VERSION_MAJOR || minor > LN_VERSION_MINOR)
        return LN_EVERSION;
    return LN_OK;
}
