/* fuzz_ring.c — fuzz target: attaching a hostile topic ring (libln/src/ring.c): the input patches
 * a fresh segment's geometry, size, write_seq, slot words, slot directory and reader slots;
 * then admin open, attach, follow, latest/queued readers' pick/finish and a writer (small and
 * hot-slot sizes) must refuse it or work in bounds and in bounded steps. */
#define _GNU_SOURCE 1
#include <assert.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "fuzz.h"
#include "ring.h"

#define LAYOUT_HASH 0xfeedull
#define FLAG_PATCH_GEOMETRY 1u
#define FLAG_RETIRED 2u
#define FLAG_HOT 4u             /* samples big enough for hot-slot reuse */
#define FLAG_PATCH_DIRECTORY 8u /* slot_of entries from the input */
#define FLAG_PATCH_READERS 16u  /* two reader slots from the input */

struct input {
    const uint8_t* p;
    size_t left;
};

static uint64_t take(struct input* in, size_t n)
{
    uint64_t v = 0;
    for (size_t i = 0; i < n && in->left > 0; i++, in->p++, in->left--)
        v |= (uint64_t)*in->p << (8 * i);
    return v;
}

/* Reads like a subscriber: pick, copy the payload, finish; at most `steps` picks. */
static void read_ring(ln_ring* ring, ln_ring_cursor* c, int steps)
{
    uint8_t copy[256];
    for (int i = 0; i < steps; i++) {
        ln_ring_slot* slot;
        uint64_t word;
        if (ln_ring_pick(ring, c, &slot, &word) != LN_OK)
            continue;
        assert((uint8_t*)slot >= ring->slots &&
               (uint8_t*)ln_ring_payload(slot) + ring->message_size <=
                   ring->slots + (uint64_t)ring->slot_count * ring->stride);
        size_t n = ring->message_size < sizeof copy ? ring->message_size : sizeof copy;
        memcpy(copy, ln_ring_payload(slot), n);
        copy[0] ^= ((const uint8_t*)ln_ring_payload(slot))[ring->message_size - 1];
        ln_ring_finish(ring, c, slot, word, 1);
    }
}

/* Writes one sample like a publisher (its slot is chosen from the hostile directory and
 * reader slots): it must land inside the ring. */
static void write_ring(ln_ring* ring)
{
    if (atomic_load(&ring->hdr->write_seq) >= LN_RING_MAX_SEQ - 1)
        return;
    ln_deadline d = ln_deadline_in(0);
    if (ln_ring_lock(ring, &d) != LN_OK)
        return;
    ln_ring_slot* slot = ln_ring_begin(ring);
    assert((uint8_t*)slot >= ring->slots &&
           (uint8_t*)ln_ring_payload(slot) + ring->message_size <=
               ring->slots + (uint64_t)ring->slot_count * ring->stride);
    memset(ln_ring_payload(slot), 0x5a, ring->message_size);
    ln_ring_commit(ring, slot);
    ln_ring_unlock(ring);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    struct input in = {data, size};
    uint32_t slots = 2 + (uint32_t)take(&in, 1) % 8;
    uint64_t message_size = 1 + take(&in, 1) % 200;
    int64_t delta = (int8_t)take(&in, 1) * (int64_t)64; /* the real segment size differs */
    unsigned flags = (unsigned)take(&in, 1);
    if (flags & FLAG_HOT)
        message_size += LN_RING_HOT_BYTES;

    char name[64];
    snprintf(name, sizeof name, "/ln-fuzz-ring-%d", (int)getpid());
    ln_ring_admin_unlink(name); /* left over by a crashed run */
    ln_ring_admin* admin;
    if (ln_ring_admin_create(&admin, name, "topic", "md", LAYOUT_HASH, message_size, slots) !=
        LN_OK)
        abort();
    ln_ring_admin_close(admin);

    /* Corrupt it through a mapping of our own. */
    uint64_t nominal = ln_ring_segment_size(message_size, slots);
    uint64_t real = (int64_t)nominal + delta > 0 ? (uint64_t)((int64_t)nominal + delta) : 0;
    int fd = shm_open(name, O_RDWR, 0);
    if (fd < 0 || ftruncate(fd, (off_t)real) != 0)
        abort();
    if (real >= ln_ring_header_bytes()) {
        uint8_t* m = mmap(NULL, real, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        if (m == MAP_FAILED)
            abort();
        ln_ring_header* h = (ln_ring_header*)m;
        if (flags & FLAG_PATCH_GEOMETRY) /* magic .. slot_stride */
            for (size_t i = 0; i < offsetof(ln_ring_header, topic); i++)
                m[i] = (uint8_t)take(&in, 1);
        atomic_store(&h->write_seq, take(&in, 8));
        atomic_store(&h->retired, (flags & FLAG_RETIRED) != 0);
        uint64_t stride = ln_ring_stride(message_size);
        for (uint32_t i = 0; i < slots; i++) {
            uint64_t at = ln_ring_header_bytes() + i * stride;
            uint64_t word = take(&in, 8);
            if (at + sizeof word <= real)
                memcpy(m + at, &word, sizeof word);
        }
        if (flags & FLAG_PATCH_DIRECTORY)
            for (uint32_t i = 0; i < slots; i++)
                atomic_store(&h->slot_of[i], (uint32_t)take(&in, 2));
        if (flags & FLAG_PATCH_READERS)
            for (uint32_t i = 0; i < 2; i++) {
                atomic_store(&h->readers[i].buffers, (uint32_t)take(&in, 1));
                atomic_store(&h->readers[i].next_seq, take(&in, 8));
                atomic_store(&h->readers[i].active, (uint32_t)take(&in, 1) & 1u);
            }
        munmap(m, real);
    }
    close(fd);

    /* The manager's and the daemon's side: open and describe it. */
    if (ln_ring_admin_open(&admin, name) == LN_OK) {
        ln_ring_info info;
        uint64_t seq;
        ln_ring_admin_info(admin, &info);
        ln_ring_admin_write_seq(admin, &seq);
        ln_ring_admin_close(admin);
    }
    /* A port's side: attach, follow a retired ring, read. */
    ln_ring ring;
    if (ln_ring_attach(&ring, name, LAYOUT_HASH, message_size) == LN_OK) {
        ln_ring_follow(&ring); /* no valid successor: refused */
        ln_ring_cursor latest = {.next = take(&in, 8), .buffers = 1, .reader = -1};
        read_ring(&ring, &latest, 8);
        ln_ring_cursor queued = {
            .next = take(&in, 8), .buffers = 2 + (uint32_t)take(&in, 1) % 16, .reader = -1};
        read_ring(&ring, &queued, 8);
        write_ring(&ring);
        read_ring(&ring, &latest, 2);
        read_ring(&ring, &queued, 2);
        ln_ring_detach(&ring);
    }
    ln_ring_admin_unlink(name);
    return 0;
}

/* ---- seeds: rings with a few committed samples ------------------------------------------- */

void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    uint8_t buf[4 + 48 + 8 + 8 * 9 + 17];
    struct ln_ring_header h;
    memset(&h, 0, sizeof h);
    h.magic = LN_RING_MAGIC;
    h.version = LN_RING_VERSION;
    h.header_size = (uint32_t)ln_ring_header_bytes();
    h.layout_hash = LAYOUT_HASH;
    for (int variant = 0; variant < 3; variant++) {
        uint32_t slots = variant == 0 ? 2 : 4 + (uint32_t)variant;
        uint64_t message_size = variant == 0 ? 8 : 100;
        uint64_t write_seq = variant == 2 ? 23 : 3;
        size_t n = 0;
        buf[n++] = (uint8_t)(slots - 2);
        buf[n++] = (uint8_t)(message_size - 1);
        buf[n++] = 0;
        buf[n++] = variant == 1 ? FLAG_PATCH_GEOMETRY : 0;
        if (variant == 1) {
            h.message_size = message_size;
            h.segment_size = ln_ring_segment_size(message_size, slots);
            h.slot_count = slots;
            h.slot_stride = (uint32_t)ln_ring_stride(message_size);
            memcpy(buf + n, &h, offsetof(ln_ring_header, topic));
            n += offsetof(ln_ring_header, topic);
        }
        memcpy(buf + n, &write_seq, 8);
        n += 8;
        for (uint32_t i = 0; i < slots; i++) { /* slot i holds the newest sample that maps to it */
            uint64_t seq = write_seq - (write_seq + slots - i) % slots;
            uint64_t word = LN_SLOT_WORD(seq, i == 0 ? LN_SLOT_WRITING : LN_SLOT_COMMITTED);
            memcpy(buf + n, &word, 8);
            n += 8;
        }
        uint64_t next = write_seq - 1;
        memcpy(buf + n, &next, 8);
        memcpy(buf + n + 8, &next, 8);
        buf[n + 16] = 3;
        n += 17;
        char name[32];
        snprintf(name, sizeof name, "ring_%d", variant);
        emit(name, buf, n);
    }
}
