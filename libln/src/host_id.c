/* host_id.c — this host's identity, ln_host_id(): what clients tell the manager in HELLO and
 * providers register with their services, so that peers on the same host are told apart from
 * those elsewhere (Unix socket or TCP, shared memory or forwarding). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ln_admin.h"
#include "proto.h"

/* Cut s (a string of len bytes that was truncated) back to a UTF-8 character boundary, so
 * the identity still encodes as a protocol str. */
static void cut_at_boundary(char* s, size_t len)
{
    for (int k = 0; k < 3 && len > 0 && !ln_utf8_valid(s, len); k++)
        s[--len] = '\0';
}

void ln_host_id(char* out, size_t size)
{
    if (out == NULL || size == 0)
        return;
    const char* env = getenv("LN_HOST_ID");
    if (env != NULL && *env != '\0') {
        if ((size_t)snprintf(out, size, "%s", env) >= size)
            cut_at_boundary(out, strlen(out));
        return;
    }
    char host[256] = "";
    char boot[64] = "";
    if (gethostname(host, sizeof host - 1) != 0)
        host[0] = '\0';
    FILE* f = fopen("/proc/sys/kernel/random/boot_id", "re");
    if (f != NULL) {
        if (fgets(boot, sizeof boot, f) == NULL)
            boot[0] = '\0';
        fclose(f);
        boot[strcspn(boot, "\n")] = '\0';
    }
    if ((size_t)snprintf(out, size, "%.200s/%.40s", host, boot) >= size)
        cut_at_boundary(out, strlen(out));
}
