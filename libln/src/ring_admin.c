/* ring_admin.c — what the manager does to topic rings: create and initialise them, keep the
 * port counts and reader slots, hand a topic over to a bigger successor, remove them.  The
 * manager maps only the header of a segment, never its slots. */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client_internal.h"
#include "futex.h"
#include "naming.h"
#include "bell.h"
#include "ring.h"

#define LN_ADMIN_MAGIC 0x4c4e5241u

struct ln_ring_admin {
    uint32_t magic;
    ln_map map;
    ln_ring_header* hdr;
};

static int check(const ln_ring_admin* a)
{
    if (!a || a->magic != LN_ADMIN_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid ring admin handle");
    return LN_OK;
}

uint64_t ln_ring_segment_size(uint64_t message_size, uint32_t slots)
{
    return ln_ring_header_bytes() + (uint64_t)slots * ln_ring_stride(message_size);
}

static int init_mutex(pthread_mutex_t* m)
{
    pthread_mutexattr_t attr;
    int rc = pthread_mutexattr_init(&attr);
    if (rc == 0)
        rc = pthread_mutexattr_setpshared(&attr, PTHREAD_PROCESS_SHARED);
    if (rc == 0)
        rc = pthread_mutexattr_setrobust(&attr, PTHREAD_MUTEX_ROBUST);
    if (rc == 0)
        rc = pthread_mutex_init(m, &attr);
    pthread_mutexattr_destroy(&attr);
    return rc;
}

int ln_ring_admin_create(ln_ring_admin** out, const char* shm_name, const char* topic,
                         const char* md_name, uint64_t layout_hash, uint64_t message_size,
                         uint32_t slots)
{
    if (!out || !shm_name || !topic || !md_name)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_admin_create: NULL argument");
    *out = NULL;
    if (strlen(topic) >= LN_RING_NAME_MAX || strlen(md_name) >= LN_RING_NAME_MAX)
        return ln_set_error(NULL, LN_EINVAL, "topic or md name longer than %d bytes",
                            LN_RING_NAME_MAX - 1);
    if (slots < 2 || slots > LN_RING_MAX_SLOTS || message_size == 0 ||
        ln_ring_stride(message_size) == 0 || ln_ring_stride(message_size) > UINT32_MAX)
        return ln_set_error(NULL, LN_ELIMIT, "ring of %u slots of %llu bytes is out of range",
                            slots, (unsigned long long)message_size);
    ln_ring_admin* a = calloc(1, sizeof(*a));
    if (!a)
        return ln_set_error(NULL, LN_ENOMEM, "out of memory");
    uint64_t size = ln_ring_segment_size(message_size, slots);
    int rc = ln_shm_create(shm_name, size, ln_ring_header_bytes(), &a->map);
    if (rc != LN_OK) {
        free(a);
        return rc;
    }
    ln_ring_header* h = a->map.addr; /* fresh pages are zero: counters, readers, futexes */
    h->version = LN_RING_VERSION;
    h->header_size = (uint32_t)ln_ring_header_bytes();
    h->layout_hash = layout_hash;
    h->message_size = message_size;
    h->segment_size = size;
    h->slot_count = slots;
    h->slot_stride = (uint32_t)ln_ring_stride(message_size);
    snprintf(h->topic, sizeof(h->topic), "%s", topic);
    snprintf(h->md_name, sizeof(h->md_name), "%s", md_name);
    rc = init_mutex(&h->write_lock);
    if (rc != 0) {
        rc = ln_set_errno_error(NULL, rc, "cannot initialise the write lock of '%s'", shm_name);
        ln_shm_unmap(&a->map);
        ln_shm_unlink(shm_name);
        free(a);
        return rc;
    }
    /* Slots start at sequence 0 (zero pages), which no sample ever has; the directory puts
     * sample n in slot n % slots until writers move samples to hot slots. */
    for (uint32_t i = 0; i < slots; i++)
        atomic_store_explicit(&h->slot_of[i], i, memory_order_relaxed);
    atomic_store_explicit((_Atomic uint64_t*)&h->magic, LN_RING_MAGIC, memory_order_release);
    a->magic = LN_ADMIN_MAGIC;
    a->hdr = h;
    *out = a;
    return LN_OK;
}

int ln_ring_admin_open(ln_ring_admin** out, const char* shm_name)
{
    if (!out || !shm_name)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_admin_open: NULL argument");
    *out = NULL;
    ln_ring_admin* a = calloc(1, sizeof(*a));
    if (!a)
        return ln_set_error(NULL, LN_ENOMEM, "out of memory");
    uint64_t size = 0;
    int rc = ln_shm_open(shm_name, ln_ring_header_bytes(), &a->map, &size);
    if (rc == LN_EPROTOCOL) /* shorter than a header */
        rc = ln_set_error(NULL, LN_EPROTOCOL,
                          "shared memory '%s' is not a usable topic ring: "
                          "%llu bytes is too small for a ring header",
                          shm_name, (unsigned long long)size);
    if (rc != LN_OK)
        goto fail;
    if ((rc = ln_ring_check_header(a->map.addr, size, shm_name)) != LN_OK)
        goto fail;
    a->hdr = a->map.addr;
    a->magic = LN_ADMIN_MAGIC;
    *out = a;
    return LN_OK;
fail:
    ln_shm_unmap(&a->map);
    free(a);
    return rc;
}

void ln_ring_admin_close(ln_ring_admin* a)
{
    if (check(a) != LN_OK)
        return;
    ln_shm_unmap(&a->map);
    a->magic = 0;
    free(a);
}

int ln_ring_admin_unlink(const char* shm_name)
{
    if (!shm_name)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_admin_unlink: NULL name");
    return ln_shm_unlink(shm_name);
}

int ln_ring_admin_set_counts(ln_ring_admin* a, uint32_t publishers, uint32_t subscribers)
{
    int rc = check(a);
    if (rc != LN_OK)
        return rc;
    uint32_t before =
        atomic_exchange_explicit(&a->hdr->publishers, publishers, memory_order_seq_cst);
    atomic_store_explicit(&a->hdr->subscribers, subscribers, memory_order_relaxed);
    if ((before == 0) != (publishers == 0))
        ln_ring_ring_bells(a->hdr, 1); /* waitsets watching the topic's liveliness */
    return LN_OK;
}

/* Copies a name field of the header, which another process may have left without a NUL. */
static void copy_name(char* out, const char* field)
{
    memcpy(out, field, LN_RING_NAME_MAX);
    out[LN_RING_NAME_MAX - 1] = '\0';
}

int ln_ring_admin_info(ln_ring_admin* a, ln_ring_info* out)
{
    int rc = check(a);
    if (rc != LN_OK)
        return rc;
    if (out == NULL)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_admin_info: out is NULL");
    _Static_assert(sizeof out->topic == LN_RING_NAME_MAX, "ln_ring_info name size");
    const ln_ring_header* h = a->hdr;
    memset(out, 0, sizeof *out);
    copy_name(out->topic, h->topic);
    copy_name(out->md_name, h->md_name);
    out->layout_hash = h->layout_hash;
    out->message_size = h->message_size;
    out->slot_count = h->slot_count;
    out->retired = atomic_load_explicit(&h->retired, memory_order_acquire);
    if (out->retired)
        copy_name(out->successor, h->successor);
    out->write_seq = atomic_load_explicit(&h->write_seq, memory_order_acquire);
    out->publishers = atomic_load_explicit(&h->publishers, memory_order_relaxed);
    out->subscribers = atomic_load_explicit(&h->subscribers, memory_order_relaxed);
    for (uint32_t i = 0; i < LN_RING_MAX_READERS; i++)
        if (atomic_load_explicit(&h->readers[i].active, memory_order_acquire))
            out->active_readers |= (uint64_t)1 << i;
    return LN_OK;
}

int ln_ring_admin_write_seq(ln_ring_admin* a, uint64_t* seq)
{
    int rc = check(a);
    if (rc != LN_OK)
        return rc;
    if (seq == NULL)
        return ln_set_error(NULL, LN_EINVAL, "ln_ring_admin_write_seq: seq is NULL");
    *seq = atomic_load_explicit(&a->hdr->write_seq, memory_order_acquire);
    return LN_OK;
}

int ln_ring_admin_reserve_reader(ln_ring_admin* a, uint32_t index, int32_t pid, uint32_t buffers)
{
    int rc = check(a);
    if (rc != LN_OK)
        return rc;
    if (index >= LN_RING_MAX_READERS || buffers == 0 || buffers >= a->hdr->slot_count)
        return ln_set_error(NULL, LN_EINVAL,
                            "reader slot %u with %u buffers does not fit a ring "
                            "of %u slots",
                            index, buffers, a->hdr->slot_count);
    ln_ring_reader* r = &a->hdr->readers[index];
    if (atomic_load_explicit(&r->pid, memory_order_relaxed) != pid)
        ln_ring_clear_bell(a->hdr, index); /* left by an earlier subscriber (same pid: taken
                                            * back after a manager restart, bell and all) */
    atomic_store_explicit(&r->pid, pid, memory_order_relaxed);
    atomic_store_explicit(&r->buffers, buffers, memory_order_relaxed);
    atomic_store_explicit(&r->next_seq,
                          atomic_load_explicit(&a->hdr->write_seq, memory_order_seq_cst) + 1,
                          memory_order_seq_cst);
    atomic_store_explicit(&r->active, 1, memory_order_release);
    return LN_OK;
}

static void wake_publishers(ln_ring_header* h) { ln_futex_bump_wake(&h->space_futex); }

int ln_ring_admin_release_reader(ln_ring_admin* a, uint32_t index)
{
    int rc = check(a);
    if (rc != LN_OK)
        return rc;
    if (index >= LN_RING_MAX_READERS)
        return ln_set_error(NULL, LN_EINVAL, "reader slot %u out of range", index);
    atomic_store_explicit(&a->hdr->readers[index].active, 0, memory_order_seq_cst);
    ln_ring_clear_bell(a->hdr, index);
    wake_publishers(a->hdr); /* a publisher may be waiting for this (dead) reader */
    return LN_OK;
}

int ln_ring_admin_retire(ln_ring_admin* a, ln_ring_admin* successor, const char* successor_name,
                         double timeout)
{
    int rc = check(a);
    if (rc == LN_OK)
        rc = check(successor);
    if (rc != LN_OK)
        return rc;
    if (!successor_name || strlen(successor_name) >= LN_RING_NAME_MAX)
        return ln_set_error(NULL, LN_EINVAL, "bad successor name");
    ln_ring_header* old = a->hdr;
    ln_ring_header* h = successor->hdr;
    ln_ring ring = {.hdr = old}; /* the lock helpers need only the header */
    ln_deadline d = ln_deadline_in(timeout);
    rc = ln_ring_lock(&ring, &d); /* no publisher writes to the old ring after this */
    if (rc != LN_OK)
        return rc;
    for (uint32_t i = 0; i < LN_RING_MAX_READERS; i++) {
        ln_ring_reader* from = &old->readers[i];
        if (!atomic_load_explicit(&from->active, memory_order_acquire))
            continue;
        ln_ring_reader* to = &h->readers[i];
        atomic_store_explicit(&to->pid, atomic_load(&from->pid), memory_order_relaxed);
        atomic_store_explicit(&to->buffers, atomic_load(&from->buffers), memory_order_relaxed);
        atomic_store_explicit(&to->next_seq, atomic_load(&from->next_seq), memory_order_relaxed);
        atomic_store_explicit(&to->active, 1, memory_order_release);
    }
    atomic_store_explicit(&h->publishers, atomic_load(&old->publishers), memory_order_relaxed);
    atomic_store_explicit(&h->subscribers, atomic_load(&old->subscribers), memory_order_relaxed);
    atomic_store_explicit(&h->write_seq, atomic_load(&old->write_seq), memory_order_seq_cst);
    snprintf(old->successor, sizeof(old->successor), "%s", successor_name);
    atomic_store_explicit(&old->retired, 1, memory_order_seq_cst);
    ln_ring_unlock(&ring);
    /* Sleeping readers and waiting publishers must notice the move. */
    ln_futex_bump_wake(&old->data_futex);
    ln_ring_ring_bells(old, 1); /* waitsets move their subscribers along */
    wake_publishers(old);
    return LN_OK;
}

int ln_ring_admin_purge_instance(const char* instance)
{
    if (!instance || !*instance)
        return ln_set_error(NULL, LN_EINVAL, "no instance name for purging segments");
    char full[LN_RING_NAME_MAX];
    if (ln_name_segment_prefix(instance, full, sizeof full) != LN_OK)
        return ln_set_error(NULL, LN_EINVAL, "instance name too long");
    const char* prefix = full + 1; /* as /dev/shm lists it: without the leading '/' */
    size_t plen = strlen(prefix);
    DIR* dir = opendir("/dev/shm");
    if (!dir)
        return ln_set_errno_error(NULL, errno, "cannot list /dev/shm");
    int removed = 0, rc = LN_OK;
    struct dirent* e;
    while ((e = readdir(dir)) != NULL) {
        if (strncmp(e->d_name, prefix, plen) != 0)
            continue;
        char name[LN_RING_NAME_MAX + 2];
        snprintf(name, sizeof(name), "/%s", e->d_name);
        rc = ln_shm_unlink(name);
        if (rc != LN_OK)
            break;
        removed++;
    }
    closedir(dir);
    return rc != LN_OK ? rc : removed;
}
