/* shm.h — the one place that creates, maps and removes POSIX shared-memory segments.
 * errno is mapped to LN_E* codes here, next to the system calls, with the segment name in
 * the error text.  The creator of a segment (the manager) is the one that unlinks it. */
#ifndef LN_SHM_H
#define LN_SHM_H

#include <stddef.h>
#include <stdint.h>

typedef struct ln_map {
    void* addr;
    size_t len;
} ln_map;

/* Create `name` (must not exist) with `size` bytes reserved up front (so a full /dev/shm is an
 * error now, not a SIGBUS later) and map its first `map_len` bytes.  Mode 0600. */
int ln_shm_create(const char* name, uint64_t size, size_t map_len, ln_map* out);
/* Map an existing segment: all of it (map_len 0: a ring's data, with its page tables filled at
 * once and huge pages advised, see shm.c) or its first map_len bytes.  *size_out (may be NULL)
 * receives the segment's size (also when it is too small to map, LN_EPROTOCOL).
 * LN_ENOTFOUND if there is no segment of that name. */
int ln_shm_open(const char* name, size_t map_len, ln_map* out, uint64_t* size_out);
void ln_shm_unmap(ln_map* map);
int ln_shm_unlink(const char* name);

#endif /* LN_SHM_H */
