/* shm.c — POSIX shared-memory segments: create (with reserved pages), map, unmap, unlink.
 * Every failure becomes an LN_E* code plus a last-error text that names the segment. */
#include "shm.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "client_internal.h"

/* Segments of at least this size are offered transparent huge pages (2 MiB on x86-64). */
#define LN_SHM_HUGE_MIN ((size_t)2 << 20)

/* `data`: a publisher's or subscriber's mapping of a whole ring.  Its page tables are filled
 * now (MAP_POPULATE), so that no sample ever pays a page fault on the first touch of a slot:
 * the pages exist already (posix_fallocate at creation), only this process's mapping of them
 * is made here instead of one fault per 4 KiB page in the data path.  Where /dev/shm is
 * mounted with huge=within_size (or always) the pages are 2 MiB ones already: 512 times fewer
 * page-table entries and TLB misses.  Large rings are also advised for huge pages, so that
 * with huge=advise (where the creation's allocation got small pages) khugepaged may merge
 * them later. */
static int map_fd(int fd, const char* name, size_t len, int data, ln_map* out)
{
    int flags = MAP_SHARED | (data ? MAP_POPULATE : 0);
    void* addr = mmap(NULL, len, PROT_READ | PROT_WRITE, flags, fd, 0);
    if (addr == MAP_FAILED)
        return ln_set_errno_error(NULL, errno, "mmap of shared memory '%s' (%zu bytes)", name, len);
#ifdef MADV_HUGEPAGE
    if (data && len >= LN_SHM_HUGE_MIN)
        (void)madvise(addr, len, MADV_HUGEPAGE); /* advice only: EINVAL where THP is off */
#endif
    out->addr = addr;
    out->len = len;
    return LN_OK;
}

int ln_shm_create(const char* name, uint64_t size, size_t map_len, ln_map* out)
{
    int rc;
    if (size > (uint64_t)PTRDIFF_MAX || map_len > size)
        return ln_set_error(NULL, LN_ETOOBIG, "shared memory '%s': %llu bytes is too big", name,
                            (unsigned long long)size);
    int fd = shm_open(name, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0)
        return ln_set_errno_error(NULL, errno, "cannot create shared memory '%s'", name);
    if (ftruncate(fd, (off_t)size) != 0) {
        rc = ln_set_errno_error(NULL, errno, "cannot size shared memory '%s' to %llu bytes", name,
                                (unsigned long long)size);
        goto fail;
    }
    /* Reserve the pages now: tmpfs would otherwise kill the first writer that touches a page
     * beyond the space left with SIGBUS. */
    rc = posix_fallocate(fd, 0, (off_t)size);
    if (rc != 0) {
        rc = ln_set_errno_error(NULL, rc == ENOSPC ? ENOMEM : rc,
                                "cannot reserve %llu bytes of shared memory for '%s'",
                                (unsigned long long)size, name);
        goto fail;
    }
    rc = map_fd(fd, name, map_len, 0, out);
    if (rc != LN_OK)
        goto fail;
    close(fd);
    return LN_OK;
fail:
    close(fd);
    shm_unlink(name);
    return rc;
}

int ln_shm_open(const char* name, size_t map_len, ln_map* out, uint64_t* size_out)
{
    struct stat st;
    int rc;
    int fd = shm_open(name, O_RDWR | O_CLOEXEC, 0);
    if (fd < 0 && errno == ENOENT)
        return ln_set_error(NULL, LN_ENOTFOUND, "there is no shared memory '%s'", name);
    if (fd < 0)
        return ln_set_errno_error(NULL, errno, "cannot open shared memory '%s'", name);
    if (fstat(fd, &st) != 0) {
        rc = ln_set_errno_error(NULL, errno, "cannot stat shared memory '%s'", name);
        goto done;
    }
    if (size_out)
        *size_out = (uint64_t)st.st_size;
    int data = map_len == 0;
    if (data)
        map_len = (size_t)st.st_size;
    if (map_len == 0 || (uint64_t)st.st_size < map_len) {
        rc = ln_set_error(NULL, LN_EPROTOCOL, "shared memory '%s' is %lld bytes, expected %zu",
                          name, (long long)st.st_size, map_len);
        goto done;
    }
    rc = map_fd(fd, name, map_len, data, out);
done:
    close(fd);
    return rc;
}

void ln_shm_unmap(ln_map* map)
{
    if (map->addr)
        munmap(map->addr, map->len);
    map->addr = NULL;
    map->len = 0;
}

int ln_shm_unlink(const char* name)
{
    if (shm_unlink(name) != 0 && errno != ENOENT)
        return ln_set_errno_error(NULL, errno, "cannot remove shared memory '%s'", name);
    return LN_OK;
}
