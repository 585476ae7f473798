/* ln/pull.h — the tiny pull-topic consumer: subscribes to a topic served by an ln_daemon (or
 * any NDN producer that names samples the same way) by pulling it with NDN Interests,
 * adapting its timeout with Dynamic Interest Timeout (DIT) and, as options, the hardenings
 * of docs/pull.md.  Portable C99: no malloc, no threads, no system calls in here; the
 * caller passes the clock (ms), a send function and the bytes it received.  One
 * subscription is one fixed-size struct the caller owns (static, stack, or a global). */
#ifndef LN_PULL_H
#define LN_PULL_H

#include <stddef.h>
#include <stdint.h>

#include "ndn.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LN_PULL_MAX_WINDOW 16 /* outstanding Interests per subscription, at most */
#define LN_PULL_MAX_NAME 96   /* bytes of the encoded /<prefix>/<topic> name value */
/* The largest Interest it sends: 2 + Name (2 + name + a SequenceNum of 2 + 8 bytes, or sync's
 * 6 and CanBePrefix, MustBeFresh) + Nonce (6) + InterestLifetime (2 + 4): 122 bytes. */
#define LN_PULL_TX_BYTES (4 + LN_PULL_MAX_NAME + 10 + 6 + 6)
#define LN_PULL_REFRESH_SPAN 64 /* samples after a loss during which REFRESH is on */

/* Hardenings (docs/pull.md); 0 is DIT exactly as the seed defines it. */
enum {
    LN_PULL_SLOT_OFFSET = 1 << 0,  /* slot j times out after t + (j-1)·P̂ (EWMA of arrivals) */
    LN_PULL_SKIP_OLD = 1 << 1,     /* abandon a pending seq once a newer one is delivered */
    LN_PULL_NACK_JUMP = 1 << 2,    /* on a NACK or a newer latest-seq header, jump there */
    LN_PULL_SYNC_QUARTER = 1 << 3, /* apply the t/4 rule to sync replies too */
    LN_PULL_KARN = 1 << 4,         /* never halve t on the reply to a retransmission */
    LN_PULL_SYNC_SLOTS = 1 << 5,   /* while syncing, the slots ask for latest+1.. as well */
    LN_PULL_REFRESH = 1 << 6,      /* on a sample, send older pending Interests once more
                                     (while a loss was seen in the last LN_PULL_REFRESH_SPAN) */
    LN_PULL_AUTO_WINDOW = 1 << 7,  /* window in effect: ceil(SRTT/P̂) + `window` */
};

typedef struct ln_pull_options {
    uint32_t t_min_ms;  /* floor of t (seed: 10) */
    uint32_t t_max_ms;  /* ceiling and start of t (seed: 2000; hardened: the control deadline) */
    uint8_t window;     /* k outstanding Interests, 1..LN_PULL_MAX_WINDOW (seed: 1); with
                            LN_PULL_AUTO_WINDOW the spare ones */
    uint8_t boot_after; /* re-bootstrap (sync) after this many consecutive timeouts (seed: 1) */
    uint16_t flags;     /* LN_PULL_* hardenings */
    uint32_t poll_ms;   /* > 0: no DIT, a fixed-rate poll of /sync every poll_ms (baseline;
                           not in a device build, -DLN_NDN_CONSUMER: LN_NDN_EINVAL) */
} ln_pull_options;

/* The seed's DIT: t in [10 ms, 2 s], k = 1, every timeout re-bootstraps, no hardenings. */
LN_NDN_EXPORT void ln_pull_options_naive(ln_pull_options* o);
/* All hardenings with k = 3, t_max = deadline_ms, t_min = 10 ms, boot_after = 3. */
LN_NDN_EXPORT void ln_pull_options_hardened(ln_pull_options* o, uint32_t deadline_ms);

/* Callbacks.  `send` puts one packet on the wire (its result is ignored: a lost packet is
 * a timeout).  `data` gets each sample once, in increasing seq order (older ones that
 * arrive late are dropped: latest-value semantics). */
typedef void (*ln_pull_send_fn)(void* user, const uint8_t* packet, size_t size);
typedef void (*ln_pull_data_fn)(void* user, uint64_t seq, const uint8_t* payload, size_t size,
                                uint64_t publish_us);
enum { LN_PULL_EV_TIMEOUT = 1, LN_PULL_EV_NACK = 2, LN_PULL_EV_SYNC = 3 };
typedef void (*ln_pull_event_fn)(void* user, int event, uint64_t seq, uint32_t t_ms);

typedef struct ln_pull_stats {
    uint32_t interests; /* sent, sync and retransmissions included */
    uint32_t syncs;     /* sync Interests sent */
    uint32_t data;      /* samples delivered */
    uint32_t timeouts;
    uint32_t nacks;
    uint32_t late;      /* Data for a seq no longer wanted (dropped) */
    uint32_t bad;       /* packets that did not decode or did not belong to us */
    uint32_t refreshes; /* pending Interests sent once more on a sample (LN_PULL_REFRESH) */
    uint32_t rejected;  /* Data whose signature did not verify (ln_pull_set_verify_key) */
} ln_pull_stats;

/* A seq as a subscription keeps it: the producer's 64-bit seq or, in a device build
 * (-DLN_NDN_CONSUMER), 32 bits counted from ln_pull_sub.seq_base (the callbacks and the
 * names sent still carry the 64-bit seqs; docs/pull.md, "Sizes", has the range it follows) */
#ifdef LN_NDN_CONSUMER
typedef uint32_t ln_pull_seq;
#else
typedef uint64_t ln_pull_seq;
#endif

typedef struct ln_pull_slot {
    ln_pull_seq seq; /* the name pending in this slot; 0: free (seqs start at 1) */
    uint32_t sent_ms;
    uint32_t nonce;
} ln_pull_slot;
/* A slot's ln_pull_sub.slot_state: the times its name was sent again after a timeout
 * (saturating), and flags.  Beside the slots, not in them: 16 bytes instead of 24 a slot. */
#define LN_PULL_SLOT_RETRIES 0x3f
#define LN_PULL_SLOT_REFRESHED 0x40 /* sent once more on a sample (LN_PULL_REFRESH) */
#define LN_PULL_SLOT_PUBLISHED 0x80 /* its seq was published when it was sent */

/* One subscription; treat the fields as private (they are public only so that the caller
 * can own the memory without malloc). */
typedef struct ln_pull_sub {
    /* The fields used most come first: a Cortex-M0 reaches a byte at offsets below 32 and a
     * word below 128 in one instruction. */
    ln_pull_options opt;
    uint8_t syncing; /* a sync Interest is pending */
    uint8_t timeouts_in_row;
    uint8_t window;     /* the window in effect (opt.window, or more: AUTO_WINDOW) */
    uint8_t since_loss; /* samples delivered since the last loss seen (saturates at 255) */
    uint16_t name_size;
    uint32_t t_ms; /* the current DIT timeout */
    uint32_t sync_sent_ms;
    uint32_t sync_nonce;
    uint32_t period_ewma_us; /* P̂ */
    uint32_t last_arrival_ms;
    uint32_t rng;     /* xorshift32 state for nonces */
    uint32_t srtt_us; /* smoothed RTT of Interests for published seqs; 0: none yet */
    ln_pull_send_fn send;
    ln_pull_data_fn on_data;
    ln_pull_event_fn on_event;
    void* user;
    ln_pull_seq delivered_seq; /* newest seq handed to on_data; 0: none */
    ln_pull_seq next_seq;      /* the next seq to ask for */
    ln_pull_seq latest_seq;    /* the producer's newest, as last reported; 0: unknown */
#ifdef LN_NDN_CONSUMER
    uint64_t seq_base; /* a kept seq s is the producer's seq_base + s */
#endif
    ln_pull_stats stats;
    uint8_t slot_state[LN_PULL_MAX_WINDOW]; /* LN_PULL_SLOT_* of each slot */
    ln_pull_slot slots[LN_PULL_MAX_WINDOW];
    uint8_t name[LN_PULL_MAX_NAME]; /* encoded /<prefix>/<topic> */
    const uint8_t* key;             /* HMAC-SHA256 key of ln_pull_set_verify_key; NULL: none */
    size_t key_size;
} ln_pull_sub;

/* Sets up `s` for the topic `uri` ("/<prefix>/<topic>", e.g. "/ln/robot/arm.state") and
 * sends the first sync Interest.  `seed` seeds the nonces (any value; 0 is taken as 1).
 * LN_NDN_EINVAL for bad options, LN_NDN_ENAME / LN_NDN_ESPACE for a bad or too long name. */
LN_NDN_EXPORT int ln_pull_start(ln_pull_sub* s, const char* uri, const ln_pull_options* o,
                                ln_pull_send_fn send, ln_pull_data_fn on_data,
                                ln_pull_event_fn on_event, void* user, uint32_t now_ms,
                                uint32_t seed);
/* The same with the topic's name already encoded: `name` is the value of the NDN Name TLV
 * of /<prefix>/<topic> (its components, 1..LN_PULL_MAX_NAME bytes), e.g. from
 * ln_ndn_name_from_uri at build time.  A device build compiled with -DLN_PULL_NO_URI has
 * only this one (no URI parser linked in).  LN_NDN_ENAME for a malformed name; LN_NDN_EINVAL
 * for poll_ms > 0 in a device build (-DLN_NDN_CONSUMER: no polling baseline). */
LN_NDN_EXPORT int ln_pull_start_name(ln_pull_sub* s, const uint8_t* name, size_t size,
                                     const ln_pull_options* o, ln_pull_send_fn send,
                                     ln_pull_data_fn on_data, ln_pull_event_fn on_event, void* user,
                                     uint32_t now_ms, uint32_t seed);
/* Takes one received packet: 1 if it was a reply to this subscription, 0 if it was for
 * another name (try the next subscription), or an error (counted in stats.bad; or
 * LN_NDN_ESIGNATURE, counted in stats.rejected, with a verify key). */
LN_NDN_EXPORT int ln_pull_receive(ln_pull_sub* s, const uint8_t* packet, size_t size,
                                  uint32_t now_ms);
/* Verifies every Data of the subscription from now on: only Data signed with HMAC-SHA256
 * (SignatureType 4) under `key` is taken; any other (unsigned, DigestSha256, another key,
 * tampered) is dropped, counted in stats.rejected, and ln_pull_receive returns
 * LN_NDN_ESIGNATURE.  Call it after ln_pull_start*, which clears it; the key's `size` bytes
 * stay the caller's and must outlive the subscription (or the next call).  NULL turns
 * verification off.  LN_NDN_EINVAL for a NULL `s`, or a NULL key with size > 0.  NDNLPv2
 * Nacks (link-layer, unsigned) are still taken when their nonce is one of ours.  A device
 * build (-DLN_NDN_CONSUMER) has it only with -DLN_PULL_HMAC (docs/pull.md, "Sizes"). */
LN_NDN_EXPORT int ln_pull_set_verify_key(ln_pull_sub* s, const uint8_t* key, size_t size);
/* Handles the timeouts due at now_ms; returns the ms until the next one is due (call again
 * then, or when a packet arrives). */
LN_NDN_EXPORT uint32_t ln_pull_poll(ln_pull_sub* s, uint32_t now_ms);

#ifdef __cplusplus
}
#endif
#endif
