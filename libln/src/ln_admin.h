/* ln_admin.h — libln's internal API for ln_daemon and the Python manager: topic segment
 * administration (ln_ring_admin_*), the forwarder's ring taps (ln_ring_tap_*) and the host
 * identity.  Not part of the ABI and never installed: libln.so does not export it and client
 * programs never call it.  ln_daemon and the C tests link it from libln.a; the manager's ctypes
 * layer loads libln_admin.so, the same sources built with LN_BUILD_ADMIN, which exports exactly
 * these functions and ln_last_error() (docs/building.md, "libln_admin.so"). */
#ifndef LN_ADMIN_H
#define LN_ADMIN_H

#include "ln/ln.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Visible only in libln_admin.so; hidden (like every internal function) everywhere else. */
#if defined(LN_BUILD_ADMIN) && (defined(__GNUC__) || defined(__clang__))
#define LN_ADMIN_API __attribute__((visibility("default")))
#else
#define LN_ADMIN_API
#endif

/* ==== topic segment administration (ln_manager, ln_daemon) ==================================
 * The manager (and ln_daemon for the rings of topics it forwards) creates, sizes, grows and
 * removes the shared-memory segments of topics; clients only map them.  An admin handle maps
 * only a segment's header, never its data. */
typedef struct ln_ring_admin ln_ring_admin;

LN_ADMIN_API int ln_ring_admin_create(ln_ring_admin** out, const char* shm_name, const char* topic,
                                      const char* md_name, uint64_t layout_hash,
                                      uint64_t message_size, uint32_t slots);
/* Unmaps; the segment stays until ln_ring_admin_unlink(). */
LN_ADMIN_API void ln_ring_admin_close(ln_ring_admin* admin);
LN_ADMIN_API int ln_ring_admin_unlink(const char* shm_name);
LN_ADMIN_API int ln_ring_admin_set_counts(ln_ring_admin* admin, uint32_t publishers,
                                          uint32_t subscribers);
/* Sequence number of the newest sample published into the ring (0: none yet); it carries
 * over to successors, so it counts the topic's samples.  The manager's rate watchdog. */
LN_ADMIN_API int ln_ring_admin_write_seq(ln_ring_admin* admin, uint64_t* seq);
/* What a segment's header says (ln_ring_admin_info): the manager adopts the rings a killed
 * predecessor left by it.  Strings are NUL-terminated copies. */
typedef struct ln_ring_info {
    char topic[256];
    char md_name[256];
    char successor[256]; /* set once retired */
    uint64_t layout_hash;
    uint64_t message_size;
    uint64_t write_seq;
    uint64_t active_readers; /* bit i: reader slot i is held */
    uint32_t slot_count;
    uint32_t retired;
    uint32_t publishers;
    uint32_t subscribers;
} ln_ring_info;
LN_ADMIN_API int ln_ring_admin_info(ln_ring_admin* admin, ln_ring_info* out);
/* Reserve reader slot `index` (0..63) for a subscriber process with `buffers`; release frees
 * it again (a dead subscriber stops holding back publishers that wait for subscribers). */
LN_ADMIN_API int ln_ring_admin_reserve_reader(ln_ring_admin* admin, uint32_t index, int32_t pid,
                                              uint32_t buffers);
LN_ADMIN_API int ln_ring_admin_release_reader(ln_ring_admin* admin, uint32_t index);
/* Hand the topic over to a bigger `successor` segment: reader slots and the sequence number
 * carry over, publishers and subscribers move on their next call. */
LN_ADMIN_API int ln_ring_admin_retire(ln_ring_admin* admin, ln_ring_admin* successor,
                                      const char* successor_name, double timeout);
/* Unlink every segment of `instance` ("/dev/shm/ln.<sanitized instance>.*", the instance
 * sanitized as segment names have it); returns how many, or < 0. */
LN_ADMIN_API int ln_ring_admin_purge_instance(const char* instance);
/* Slot count and bytes of a ring for `message_size` and `slots` (the manager's limit check). */
LN_ADMIN_API uint64_t ln_ring_segment_size(uint64_t message_size, uint32_t slots);
/* Map the header of an existing segment (made by an earlier process, e.g. a daemon that was
 * restarted) after checking its magic, version and geometry; LN_ENOTFOUND if there is none,
 * LN_EVERSION for a ring of another format version, LN_EPROTOCOL (ln_last_error() says what)
 * for anything that is not a consistent ring.  Free *out with ln_ring_admin_close(). */
LN_ADMIN_API int ln_ring_admin_open(ln_ring_admin** out, const char* shm_name);

/* ==== topic forwarding between hosts (ln_daemon) ===========================================
 * A tap maps a topic's ring like a port but needs no manager: the daemon of the publisher's
 * host reads samples out of it, the daemon of a subscriber's host writes them in under their
 * original sequence numbers and timestamps.  A tap holds no reader slot, so publishers never
 * wait for it; what it falls behind on is counted as lost.  It follows the ring into its
 * successor when the manager grows the topic.  Use a tap either for reading or for injecting
 * (injecting moves it to the newest ring at once, past samples a reader had not read yet),
 * from one thread at a time; different taps of one ring may be used concurrently. */
typedef struct ln_ring_tap ln_ring_tap;
#define LN_TAP_EVERY 0u  /* read: every sample in order while the ring still holds it */
#define LN_TAP_NEWEST 1u /* read: always the newest sample, skipping older ones */
/* Or'ed into the mode: start at the newest sample present at open (if any), not after it. */
#define LN_TAP_INCLUDE_NEWEST 2u
/* Map ring `shm_name` (following it to its newest successor if it is retired) after checking
 * it has layout_hash and message_size (LN_ELAYOUT if not; LN_ENOTFOUND if there is no such
 * segment; LN_EINVAL for another mode).  *out belongs to the caller: ln_ring_tap_close. */
LN_ADMIN_API int ln_ring_tap_open(ln_ring_tap** out, const char* shm_name, uint64_t layout_hash,
                                  uint64_t message_size, unsigned mode);
LN_ADMIN_API void ln_ring_tap_close(ln_ring_tap* tap);
/* Copy the next sample (per mode) into buf[message_size]: LN_OK with info (seq, timestamp_ns;
 * overruns = how many sequence numbers lie between the previous sample read and this one:
 * overwritten before the tap got to them, skipped for the newest, or never written into this
 * ring), LN_ETIMEOUT if none came within `timeout` seconds (0: poll, also LN_ETIMEOUT;
 * < 0: forever; NaN: LN_EINVAL).  A fresh tap starts after the newest sample present at
 * open (at it with LN_TAP_INCLUDE_NEWEST).  A blocked read sleeps on the ring's futex and
 * is woken by every write, inject and retirement.  On a retired ring it first reads what is
 * left there (NEWEST: its newest sample), then moves on to the successor, so EVERY loses
 * nothing to ring growth. */
LN_ADMIN_API int ln_ring_tap_read(ln_ring_tap* tap, void* buf, ln_sample_info* info,
                                  double timeout);
/* Write one sample as sequence number `seq` (numbers may jump: readers count the gap as lost)
 * with `timestamp_ns`, waking the ring's readers.  Moves to the newest successor first if
 * the ring is retired.  Never waits for queued readers (their unread samples are overwritten
 * and counted as overruns); waits at most 1 s for the topic's write lock (LN_ETIMEOUT if a
 * local publisher holds it with a loan).  LN_EOVERRUN (nothing written) if seq is not newer
 * than the ring's newest sample; LN_EINVAL if seq >= 2^62. */
LN_ADMIN_API int ln_ring_tap_inject(ln_ring_tap* tap, const void* data, uint64_t seq,
                                    int64_t timestamp_ns);
/* Zero-copy reading: the next sample (as ln_ring_tap_read) stays in the ring and *payload
 * points at its message_size bytes there.  A tap holds no reader slot, so a publisher may
 * reuse the slot meanwhile: use the bytes (e.g. hand them to send()), then
 * ln_ring_tap_release says whether they stayed intact all along (LN_OK) or were overwritten
 * (LN_EOVERRUN: what was read may be torn; the tap is past the sample either way).  One
 * borrow at a time (LN_EBUSY); ln_ring_tap_read in between is refused the same way. */
LN_ADMIN_API int ln_ring_tap_borrow(ln_ring_tap* tap, const void** payload, ln_sample_info* info,
                                    double timeout);
LN_ADMIN_API int ln_ring_tap_release(ln_ring_tap* tap);
/* Injecting in place: ln_ring_tap_inject in three steps, for a sample that arrives piece by
 * piece (received straight into the ring).  begin makes the checks of inject, takes the
 * topic's write lock and sets *payload to the slot to fill; the lock stays held until commit
 * (publishes it with timestamp_ns) or abort (the slot stays unpublished: readers never see
 * it), so fill it quickly.  All three from the thread that began.  A process killed between
 * begin and commit leaves nothing visible (the next writer recovers the lock). */
LN_ADMIN_API int ln_ring_tap_inject_begin(ln_ring_tap* tap, uint64_t seq, void** payload);
LN_ADMIN_API int ln_ring_tap_inject_commit(ln_ring_tap* tap, int64_t timestamp_ns);
LN_ADMIN_API int ln_ring_tap_inject_abort(ln_ring_tap* tap);
/* Newest sequence number of the topic, 0 if none: of the ring the tap is on, or of its
 * newest successor if that one is retired (without moving the tap).  0 for a bad handle. */
LN_ADMIN_API uint64_t ln_ring_tap_write_seq(ln_ring_tap* tap);
/* How many samples the ring the tap is on holds (its slots); 0 for a bad handle.  A sample
 * `lag` sequence numbers behind ln_ring_tap_write_seq is overwritten after about
 * slots - 1 - lag more writes. */
LN_ADMIN_API uint32_t ln_ring_tap_slots(const ln_ring_tap* tap);
/* The name of the segment the tap is on now (changes when it followed a successor); owned
 * by the tap.  NULL for a bad handle. */
LN_ADMIN_API const char* ln_ring_tap_segment(const ln_ring_tap* tap);

/* This host's identity: $LN_HOST_ID if set, else "hostname/boot_id".  Clients tell it to the
 * manager, which maps it to the host's ln_daemon; services compare it to pick Unix socket or
 * TCP.  Writes at most size bytes including the NUL. */
LN_ADMIN_API void ln_host_id(char* out, size_t size);

#ifdef __cplusplus
}
#endif

#endif /* LN_ADMIN_H */
