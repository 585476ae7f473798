/* naming.c — the naming rules of naming.h: sanitized instance, segment names, the runtime
 * directory and service socket names. */
#include "naming.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ln/ln.h"

size_t ln_name_instance(const char* instance, char* out, size_t size)
{
    size_t n = 0;
    for (const unsigned char* p = (const unsigned char*)instance; *p != '\0'; p++) {
        unsigned char c = *p;
        if ((c & 0xc0) == 0x80)
            continue; /* a continuation byte: its character has its '_' already */
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                 c == '_' || c == '-';
        if (n + 1 < size)
            out[n] = ok ? (char)c : '_';
        n++;
    }
    if (size > 0)
        out[n < size ? n : size - 1] = '\0';
    return n;
}

/* LN_OK if snprintf's result `len` fitted into size bytes. */
static int fitted(int len, size_t size)
{
    return len >= 0 && (size_t)len < size ? LN_OK : LN_ETOOBIG;
}

/* Appends the sanitized instance to out, which holds `used` bytes already. */
static int put_instance(const char* instance, char* out, size_t size, size_t used)
{
    if (used >= size)
        return LN_ETOOBIG;
    size_t n = ln_name_instance(instance, out + used, size - used);
    return used + n < size ? LN_OK : LN_ETOOBIG;
}

int ln_name_segment_prefix(const char* instance, char* out, size_t size)
{
    int rc = fitted(snprintf(out, size, "/ln."), size);
    if (rc == LN_OK)
        rc = put_instance(instance, out, size, 4);
    if (rc == LN_OK) {
        size_t len = strlen(out);
        rc = fitted(snprintf(out + len, size - len, "."), size - len);
    }
    return rc;
}

int ln_name_segment(const char* instance, uint64_t topic_id, uint64_t generation, const char* tag,
                    char* out, size_t size)
{
    int rc = ln_name_segment_prefix(instance, out, size);
    if (rc != LN_OK)
        return rc;
    size_t len = strlen(out);
    int has_tag = tag != NULL && *tag != '\0';
    return fitted(snprintf(out + len, size - len, "%llu.%llu%s%s", (unsigned long long)topic_id,
                           (unsigned long long)generation, has_tag ? "." : "", has_tag ? tag : ""),
                  size - len);
}

int ln_name_runtime_dir(const char* instance, char* out, size_t size, size_t* parent_len)
{
    const char* env = getenv("LN_RUNTIME_DIR");
    const char* xdg = getenv("XDG_RUNTIME_DIR");
    int len;
    *parent_len = 0;
    if (env != NULL && *env != '\0')
        return fitted(snprintf(out, size, "%s", env), size);
    if (xdg != NULL && *xdg != '\0')
        len = snprintf(out, size, "%s/ln", xdg);
    else
        len = snprintf(out, size, "/tmp/ln-%u", (unsigned)getuid());
    if (fitted(len, size) != LN_OK)
        return LN_ETOOBIG;
    *parent_len = (size_t)len;
    if (fitted(snprintf(out + len, size - (size_t)len, "/"), size - (size_t)len) != LN_OK)
        return LN_ETOOBIG;
    return put_instance(instance, out, size, (size_t)len + 1);
}

int ln_name_service_socket(const char* dir, long pid, unsigned n, char* out, size_t size)
{
    return fitted(snprintf(out, size, "%s/svc.%ld.%u.sock", dir, pid, n), size);
}
