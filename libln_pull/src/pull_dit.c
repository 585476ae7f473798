/* pull_dit.c — the pull-topic consumer (ln/pull.h): Dynamic Interest Timeout as
 * dit_transport §1.3 defines it (flags 0, window 1, boot_after 1), the hardenings of §5.4
 * as options, a fixed-rate polling baseline (poll_ms > 0; not in a device build) and
 * HMAC-SHA256 verification of Data.  No malloc, no system calls: the caller passes the clock
 * in ms (uint32, wrap-safe), a send function and the packets it received.  docs/pull.md has
 * the rules and formulas.  Interests are written here directly, replies come decoded from
 * pull_decode.c.  Sized for small cores (docs/pull.md, "Sizes"): no division but udiv's, no
 * 64-bit multiply or shift, no large struct on the stack, 32-bit seqs in a device build. */
#include "ln/pull.h"
#include "pull_internal.h"

/* The device build verifies only with -DLN_PULL_HMAC (the "hmac" profile); the full one
 * always can. */
#if !defined(LN_NDN_CONSUMER) || defined(LN_PULL_HMAC)
#define VERIFY 1
#endif

#define BIG_MS 0x7fffffffu
/* The producer's seq of a kept one (ln_pull_seq: a device build keeps 32-bit offsets) */
#ifdef LN_NDN_CONSUMER
#define WIRE(s, seq) ((s)->seq_base + (seq))
#else
#define WIRE(s, seq) (seq)
#endif
/* The fixed-rate polling baseline (poll_ms > 0) is a yardstick for DIT, not for a device: a
 * device build leaves it out (128 bytes of Thumb code) and refuses poll_ms > 0 */
#ifdef LN_NDN_CONSUMER
#define POLL_MS(s) 0u
#define BAD_POLL(o) ((o)->poll_ms != 0)
#else
#define POLL_MS(s) ((s)->opt.poll_ms)
#define BAD_POLL(o) ((o)->poll_ms > BIG_MS)
#endif
#if defined(__GNUC__) || defined(__clang__)
#define NOINLINE __attribute__((noinline))
#else
#define NOINLINE
#endif

/* The slot_state byte of a slot (not inlined: the slot's index is a division by its size) */
NOINLINE static uint8_t* state_of(ln_pull_sub* s, const ln_pull_slot* slot)
{
    return &s->slot_state[slot - s->slots];
}
#define STATE(s, slot) (*state_of(s, slot))

LN_NDN_EXPORT void ln_pull_options_naive(ln_pull_options* o)
{
    ln_ndn_i_zero(o, sizeof *o);
    o->t_min_ms = 10;
    o->t_max_ms = 2000;
    o->window = 1;
    o->boot_after = 1;
}

LN_NDN_EXPORT void ln_pull_options_hardened(ln_pull_options* o, uint32_t deadline_ms)
{
    ln_ndn_i_zero(o, sizeof *o);
    o->t_max_ms = deadline_ms;
    o->t_min_ms = deadline_ms < 10 ? deadline_ms : 10;
    o->window = 3;
    o->boot_after = 3;
    o->flags = LN_PULL_SLOT_OFFSET | LN_PULL_SKIP_OLD | LN_PULL_NACK_JUMP | LN_PULL_SYNC_QUARTER |
               LN_PULL_KARN | LN_PULL_SYNC_SLOTS | LN_PULL_REFRESH | LN_PULL_AUTO_WINDOW;
}

/* a / b (b > 0), by shifts: no division instruction on a Cortex-M0 and libgcc's is 0.3 KiB */
static uint32_t udiv(uint32_t a, uint32_t b)
{
    uint32_t q = 0, bit = 1;
    while (b < a && !(b & 0x80000000u))
        b <<= 1, bit <<= 1;
    for (; bit; b >>= 1, bit >>= 1)
        if (a >= b)
            a -= b, q |= bit;
    return q;
}

/* xorshift32 */
static uint32_t nonce(ln_pull_sub* s)
{
    uint32_t x = s->rng;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    s->rng = x;
    return x;
}

/* ms from now until `deadline` (0 if it has passed), wrap-safe */
static uint32_t until(uint32_t now, uint32_t deadline)
{
    uint32_t d = deadline - now;
    return d > BIG_MS ? 0 : d;
}

static void event(ln_pull_sub* s, int ev, ln_pull_seq seq)
{
    if (s->on_event)
        s->on_event(s->user, ev, seq ? WIRE(s, seq) : 0, s->t_ms);
}

/* Sends an Interest for /<name>/seq=<seq>, or for /<name>/sync when seq is 0: the bytes
 * ln_ndn_encode_interest would write, written here directly (every length fits one byte:
 * the name is at most LN_PULL_MAX_NAME bytes, the Interest at most LN_PULL_TX_BYTES < 253),
 * which keeps the generic encoder out of a device's consumer. */
/* A TLV of `type` holding v big-endian in the fewest of 1, 2, 4, 8 bytes (at least `min`). */
static uint8_t* put_number(uint8_t* p, uint8_t type, uint64_t v, uint8_t min)
{
    uint32_t lo = (uint32_t)v, hi = (uint32_t)(v >> 32); /* 32-bit halves: no 64-bit shifts */
    uint8_t len = hi ? 8 : lo >> 16 || min == 4 ? 4 : lo >> 8 ? 2 : 1, i; /* min: 1 or 4 */
    *p++ = type;
    *p++ = len;
    for (i = len; i > 0; i--) {
        p[i - 1] = (uint8_t)lo;
        lo = lo >> 8 | hi << 24;
        hi >>= 8;
    }
    return p + len;
}

static void send_interest(ln_pull_sub* s, ln_pull_seq seq, uint32_t n, uint32_t lifetime)
{
    uint8_t packet[LN_PULL_TX_BYTES], *p = packet + 4;
    ln_ndn_i_copy(p, s->name, s->name_size);
    p += s->name_size;
    if (seq) { /* SequenceNum component: a NonNegativeInteger of 1, 2, 4 or 8 bytes */
        p = put_number(p, LN_NDN_T_SEQUENCE_NUM, WIRE(s, seq), 1);
        packet[3] = (uint8_t)(p - packet - 4);
    } else { /* the component "sync", then CanBePrefix, MustBeFresh */
        ln_ndn_i_copy(p, "\x08\x04sync\x21\x00\x12\x00", 10);
        packet[3] = (uint8_t)(s->name_size + 6);
        p += 10;
        s->stats.syncs++;
    }
    packet[2] = LN_NDN_T_NAME;
    p = put_number(p, LN_NDN_T_NONCE, n, 4);
    if (lifetime != LN_NDN_DEFAULT_LIFETIME_MS)
        p = put_number(p, LN_NDN_T_INTEREST_LIFETIME, lifetime, 1);
    packet[0] = LN_NDN_T_INTEREST;
    packet[1] = (uint8_t)(p - packet - 2);
    s->stats.interests++;
    s->send(s->user, packet, (size_t)(p - packet));
}

/* P̂ in ms, rounded */
static uint32_t period_ms(const ln_pull_sub* s)
{
    uint32_t q = udiv(s->period_ewma_us, 1000);
    return q + (s->period_ewma_us - q * 1000 >= 500);
}

/* The timeout of the Interest pending for `seq`: t, plus (j-1)·P̂ with SLOT_OFFSET, j being
 * seq's distance from the newest delivered sample (1..window in effect). */
static uint32_t slot_timeout(const ln_pull_sub* s, ln_pull_seq seq)
{
    /* 32 bits: t < 2^31 and (j-1)·P̂ < 15·4.3e6 cannot overflow */
    uint32_t t = s->t_ms, j;
    if ((s->opt.flags & LN_PULL_SLOT_OFFSET) && s->delivered_seq && seq > s->delivered_seq) {
        j = seq - s->delivered_seq > s->window ? s->window : (uint32_t)(seq - s->delivered_seq);
        t += (j - 1) * period_ms(s);
    }
    return t > BIG_MS ? BIG_MS : t;
}

/* When the Interest pending in `slot` times out: t_j after it was sent or, with SLOT_OFFSET,
 * after the newest sample arrived if that was later (j shrinks as samples arrive: a deep
 * slot of a large window, sent j·P̂ before its sample, must not time out before it). */
static uint32_t deadline(const ln_pull_sub* s, const ln_pull_slot* slot)
{
    uint32_t base = slot->sent_ms;
    if ((s->opt.flags & LN_PULL_SLOT_OFFSET) && s->delivered_seq &&
        (uint32_t)(s->last_arrival_ms - base) - 1u < BIG_MS)
        base = s->last_arrival_ms;
    return base + slot_timeout(s, slot->seq);
}

static ln_pull_slot* find(ln_pull_sub* s, ln_pull_seq seq)
{
    ln_pull_slot* slot;
    for (slot = s->slots; seq && slot < s->slots + LN_PULL_MAX_WINDOW; slot++)
        if (slot->seq == seq)
            return slot;
    return NULL;
}

/* Sends the Interest of `slot` (again), with a new nonce */
static void resend(ln_pull_sub* s, ln_pull_slot* slot, uint32_t now)
{
    slot->sent_ms = now;
    slot->nonce = nonce(s);
    send_interest(s, slot->seq, slot->nonce, slot_timeout(s, slot->seq));
}

static void take(ln_pull_sub* s, ln_pull_slot* slot, ln_pull_seq seq, uint32_t now)
{
    slot->seq = seq;
    /* published already: its reply is an RTT */
    STATE(s, slot) = seq <= s->latest_seq ? LN_PULL_SLOT_PUBLISHED : 0;
    resend(s, slot, now);
}

/* Puts an Interest for the next seqs into free slots until `window` are pending (never a
 * seq already pending).  A slot beyond a shrunk window runs out but is not refilled. */
static void fill(ln_pull_sub* s, uint32_t now)
{
    int i, used = 0;
    if ((s->syncing && !(s->opt.flags & LN_PULL_SYNC_SLOTS)) || POLL_MS(s))
        return;
    for (i = 0; i < LN_PULL_MAX_WINDOW; i++)
        used += s->slots[i].seq != 0;
    for (i = 0; i < LN_PULL_MAX_WINDOW && used < s->window; i++) {
        if (s->slots[i].seq)
            continue;
        while (find(s, s->next_seq))
            s->next_seq++;
        take(s, &s->slots[i], s->next_seq, now);
        s->next_seq++;
        used++;
    }
}

/* (Re-)bootstrap: abandon every slot and send /<name>/sync; with SYNC_SLOTS the slots ask
 * for latest+1.. at the same time (k + 1 chances per t instead of one). */
static void sync(ln_pull_sub* s, uint32_t now)
{
    ln_ndn_i_zero(s->slots, sizeof s->slots);
    s->syncing = 1;
    s->sync_sent_ms = now;
    s->sync_nonce = nonce(s);
    send_interest(s, 0, s->sync_nonce, POLL_MS(s) ? POLL_MS(s) : s->t_ms);
    event(s, LN_PULL_EV_SYNC, s->delivered_seq);
    if ((s->opt.flags & LN_PULL_SYNC_SLOTS) && s->latest_seq) {
        s->next_seq = (s->latest_seq > s->delivered_seq ? s->latest_seq : s->delivered_seq) + 1;
        fill(s, now);
    }
}

/* AUTO_WINDOW: the window in effect is ceil(SRTT/P̂) + k (k = opt.window): the samples
 * published during one RTT, plus k to spare (a slot lost, room for REFRESH) */
static void size_window(ln_pull_sub* s)
{
    uint32_t w = s->opt.window, p = s->period_ewma_us;
    if ((s->opt.flags & LN_PULL_AUTO_WINDOW) && p && s->srtt_us) {
        uint32_t q = udiv(s->srtt_us, p);
        w += q + (q * p != s->srtt_us);
        if (w > LN_PULL_MAX_WINDOW)
            w = LN_PULL_MAX_WINDOW;
    }
    s->window = (uint8_t)w;
}

/* An RTT sample (RFC 6298 SRTT, gain 1/8), from the immediate reply to a sync or to an
 * Interest for a seq published when it was sent, or a parked one's Δ below SRTT (an upper
 * bound of the RTT: SRTT can come down); never from a resent or refreshed one (Karn). */
/* An EWMA of gain 1/8 (the first sample taken as it is) */
NOINLINE static uint32_t ewma(uint32_t avg, uint32_t x)
{
    return !avg ? x : x >= avg ? avg + (x - avg) / 8 : avg - (avg - x) / 8;
}

static void rtt_sample(ln_pull_sub* s, uint32_t sent, uint32_t now)
{
    uint32_t r = (uint32_t)(now - sent) > 4000000u ? 4000000000u : (now - sent) * 1000u;
    s->srtt_us = ewma(s->srtt_us, r);
    size_window(s);
}

NOINLINE static void halve_if_quick(ln_pull_sub* s, uint32_t sent, uint32_t now)
{
    if (now - sent < (s->t_ms + 3) / 4) { /* 4·Δ < t, in 32 bits (t < 2^31) */
        s->t_ms /= 2;
        if (s->t_ms < s->opt.t_min_ms)
            s->t_ms = s->opt.t_min_ms;
    }
}

static void double_t(ln_pull_sub* s)
{
    s->t_ms = s->t_ms > s->opt.t_max_ms / 2 ? s->opt.t_max_ms : s->t_ms * 2;
}

static void deliver(ln_pull_sub* s, ln_pull_seq seq, const ln_ndn_pull_content* c, uint32_t now)
{
    if (s->since_loss < 255)
        s->since_loss++;
    if (s->delivered_seq && seq > s->delivered_seq) { /* P̂: EWMA (1/8) of the period */
        /* in 32 bits (no 64-bit division on small cores): gaps capped at 4e6 ms, 65535 seqs */
        ln_pull_seq d = seq - s->delivered_seq;
        uint32_t gap = now - s->last_arrival_ms, n = d > 0xffffu ? 0xffffu : (uint32_t)d;
        if (d > 1) /* a seq skipped: lost (or jumped) */
            s->since_loss = 0;
        s->period_ewma_us =
            ewma(s->period_ewma_us, udiv((gap > 4000000u ? 4000000u : gap) * 1000u, n));
    }
    s->last_arrival_ms = now;
    s->delivered_seq = seq;
    s->stats.data++;
    if (s->opt.flags & LN_PULL_SKIP_OLD) { /* a reply for these could only be late now */
        int i;
        for (i = 0; i < LN_PULL_MAX_WINDOW; i++)
            if (s->slots[i].seq <= seq)
                s->slots[i].seq = 0;
    }
    size_window(s);
    if (s->on_data)
        s->on_data(s->user, WIRE(s, seq), c->payload.data, c->payload.size, c->publish_us);
}

static void on_timeout(ln_pull_sub* s, ln_pull_slot* slot, uint32_t now)
{
    ln_pull_seq seq = slot ? slot->seq : 0;
    if (slot && s->syncing) { /* an LP Nack of a SYNC_SLOTS Interest: the sync goes on */
        slot->seq = 0;
        return;
    }
    double_t(s);
    s->stats.timeouts++;
    s->since_loss = 0;
    if (s->timeouts_in_row < 255)
        s->timeouts_in_row++;
    event(s, LN_PULL_EV_TIMEOUT, seq);
    if (!slot || s->timeouts_in_row >= s->opt.boot_after) {
        sync(s, now);
    } else { /* retransmission: the same name, a new nonce */
        uint8_t* st = state_of(s, slot);
        if ((*st & LN_PULL_SLOT_RETRIES) < LN_PULL_SLOT_RETRIES)
            (*st)++;
        resend(s, slot, now);
    }
}

LN_NDN_EXPORT int ln_pull_start_name(ln_pull_sub* s, const uint8_t* name, size_t size,
                                     const ln_pull_options* o, ln_pull_send_fn send,
                                     ln_pull_data_fn on_data, ln_pull_event_fn on_event, void* user,
                                     uint32_t now_ms, uint32_t seed)
{
    ln_ndn_bytes rest;
    ln_ndn_component c;
    int r;
    if (!s || !name || !o || !send || !o->t_min_ms || o->t_min_ms > o->t_max_ms ||
        o->t_max_ms > BIG_MS || BAD_POLL(o) || o->window - 1u >= LN_PULL_MAX_WINDOW ||
        !o->boot_after)
        return LN_NDN_EINVAL;
    if (size == 0)
        return LN_NDN_ENAME;
    if (size > LN_PULL_MAX_NAME)
        return LN_NDN_ESPACE;
    rest.data = name;
    rest.size = size;
    while ((r = ln_ndn_i_component(&rest, &c)) > 0)
        ;
    if (r < 0)
        return LN_NDN_ENAME;
    ln_ndn_i_zero(s, sizeof *s);
    ln_ndn_i_copy(s->name, name, size);
    s->name_size = (uint16_t)size;
    ln_ndn_i_copy(&s->opt, o, sizeof *o); /* not `=`: that is a memcpy call on a Cortex-M0 */
    s->send = send;
    s->on_data = on_data;
    s->on_event = on_event;
    s->user = user;
    s->t_ms = o->t_max_ms;
    s->window = o->window;
    s->next_seq = 1;
    s->rng = seed ? seed : 1;
    sync(s, now_ms);
    return LN_NDN_OK;
}

#ifndef LN_PULL_NO_URI
LN_NDN_EXPORT int ln_pull_start(ln_pull_sub* s, const char* uri, const ln_pull_options* o,
                                ln_pull_send_fn send, ln_pull_data_fn on_data,
                                ln_pull_event_fn on_event, void* user, uint32_t now_ms,
                                uint32_t seed)
{
    uint8_t name[LN_PULL_MAX_NAME];
    int size;
    if (!uri)
        return LN_NDN_EINVAL;
    size = ln_ndn_name_from_uri(name, sizeof name, uri);
    if (size < 0)
        return size;
    return ln_pull_start_name(s, name, (size_t)size, o, send, on_data, on_event, user, now_ms,
                              seed);
}
#endif

/* ---- replies -------------------------------------------------------------------------------- */
/* d·P > srtt for d > 0 (P > ⌊srtt/d⌋: no 64-bit multiply) */
static int period_beyond(ln_pull_seq d, uint32_t p, uint32_t srtt)
{
    return p && (d > srtt || p > udiv(srtt, (uint32_t)d));
}

/* A sample: the reply to /<name>/sync (sync_name) or to a slot's seq=<seq>; `latest` is
 * its latest-seq header (0: none) */
static void on_sample(ln_pull_sub* s, ln_pull_seq seq, ln_pull_seq latest,
                      const ln_ndn_pull_content* c, uint32_t now, int sync_name)
{
    ln_pull_slot* slot = NULL;
    uint32_t sent;
    uint8_t st = 0;
    int i, halve, rtt;
    if (sync_name && POLL_MS(s)) { /* polling: every reply counts, the newest delivered */
        s->syncing = 0;
        s->latest_seq = latest ? latest : seq;
        if (seq > s->delivered_seq)
            deliver(s, seq, c, now);
        else if (seq < s->delivered_seq)
            s->stats.late++;
        return;
    }
    if (sync_name) {
        if (!s->syncing) {
            s->stats.late++;
            return;
        }
        sent = s->sync_sent_ms;
        halve = s->opt.flags & LN_PULL_SYNC_QUARTER;
        rtt = s->opt.flags & LN_PULL_AUTO_WINDOW;
    } else {
        if (!(slot = find(s, seq))) {
            s->stats.late++;
            return;
        }
        sent = slot->sent_ms;
        st = STATE(s, slot);
        halve = !((s->opt.flags & LN_PULL_KARN) && (st & LN_PULL_SLOT_RETRIES));
        /* Δ is an RTT for a published seq, and at least one for a parked one: it lowers SRTT */
        rtt =
            (s->opt.flags & LN_PULL_AUTO_WINDOW) &&
            (st == LN_PULL_SLOT_PUBLISHED || (!st && (uint32_t)(now - sent) * 1000u < s->srtt_us));
    }
    if (halve)
        halve_if_quick(s, sent, now);
    if (rtt)
        rtt_sample(s, sent, now);
    s->timeouts_in_row = 0;
    s->syncing = 0; /* a sample ends a re-bootstrap too (SYNC_SLOTS) */
    s->latest_seq = latest ? latest : seq;
    if (sync_name) {
        if (!s->period_ewma_us && c->period_us) /* P̂ starts from the producer's mean period */
            s->period_ewma_us = c->period_us > 0xffffffffu ? 0xffffffffu : (uint32_t)c->period_us;
        if (seq != s->delivered_seq) /* below it: the producer started over */
            deliver(s, seq, c, now);
        s->next_seq = seq + 1;
        fill(s, now);
        return;
    }
    slot->seq = 0;
    if (seq > s->delivered_seq)
        deliver(s, seq, c, now);
    else
        s->stats.late++;
    if ((s->opt.flags & LN_PULL_NACK_JUMP) && latest > seq && s->next_seq < latest)
        s->next_seq = latest; /* behind: go straight to the newest */
    /* REFRESH (while a loss was seen in the last LN_PULL_REFRESH_SPAN samples): an Interest
     * pending for at least P̂/2, not yet resent, for a seq that is not published before a
     * new Interest could get there ((seq - newest)·P̂ > SRTT), goes out once more (new
     * nonce): a lost Interest is recovered before its sample is published */
    for (i = 0; i < LN_PULL_MAX_WINDOW && (s->opt.flags & LN_PULL_REFRESH) &&
                s->since_loss < LN_PULL_REFRESH_SPAN;
         i++) {
        ln_pull_slot* r = &s->slots[i];
        if (r->seq > s->delivered_seq && !(s->slot_state[i] & ~LN_PULL_SLOT_PUBLISHED) &&
            (uint32_t)(now - r->sent_ms) * 2000u >= s->period_ewma_us &&
            period_beyond(r->seq - s->delivered_seq, s->period_ewma_us, s->srtt_us)) {
            s->slot_state[i] |= LN_PULL_SLOT_REFRESHED;
            s->stats.refreshes++;
            resend(s, r, now);
        }
    }
    fill(s, now);
}

static void on_nack(ln_pull_sub* s, ln_pull_seq seq, ln_pull_seq latest, uint32_t now)
{
    ln_pull_slot* slot = find(s, seq);
    s->stats.nacks++;
    event(s, LN_PULL_EV_NACK, seq);
    if (seq == 0) { /* sync refused (nothing published yet): its timer runs on, or next poll */
        if (POLL_MS(s))
            s->syncing = 0;
        return;
    }
    if (!slot || !(s->opt.flags & LN_PULL_NACK_JUMP))
        return; /* the naive consumer lets the timer run out */
    s->latest_seq = latest;
    if (latest > s->delivered_seq) { /* jump to the producer's newest */
        slot->seq = 0;
        if (!find(s, latest))
            take(s, slot, latest, now);
        if (s->next_seq <= latest)
            s->next_seq = latest + 1;
        fill(s, now);
    } else if (latest == 0 || latest < s->delivered_seq) { /* no sample, or it started over */
        if (s->syncing) /* a SYNC_SLOTS Interest: the sync pending will tell */
            slot->seq = 0;
        else
            sync(s, now);
    } /* latest == delivered: seq is beyond what the producer parks; the timer retries */
}

#ifdef VERIFY
LN_NDN_EXPORT int ln_pull_set_verify_key(ln_pull_sub* s, const uint8_t* key, size_t size)
{
    if (!s || (!key && size))
        return LN_NDN_EINVAL;
    s->key = key;
    s->key_size = key ? size : 0;
    return LN_NDN_OK;
}

/* Data signed with HMAC-SHA256 under the subscription's key */
static int verified(const ln_pull_sub* s, const ln_ndn_i_reply* p)
{
    uint8_t mac[32], diff = 0;
    int i;
    if (p->signature_type != LN_NDN_SIG_HMAC_SHA256 || p->signature.size != 32)
        return 0;
    ln_ndn_hmac_sha256(s->key, s->key_size, p->signed_portion.data, p->signed_portion.size, mac);
    for (i = 0; i < 32; i++) /* in constant time */
        diff |= (uint8_t)(mac[i] ^ p->signature.data[i]);
    return !diff;
}
#endif

#ifdef LN_NDN_CONSUMER
/* A device build keeps a seq as its offset from seq_base, 1..2^32 - 2^16 (room above for the
 * window), else 0 (unknown: a name no slot has, a latest-seq header not taken).  seq_base is 0
 * at the start and moves to s - 1 at a reply s of a pending sync that is out of that range
 * (the producer started over below the base, or got 2^32 - 2^16 seqs past it). */
NOINLINE static ln_pull_seq kept(const ln_pull_sub* s, uint64_t seq)
{
    uint64_t d = seq - s->seq_base;
    uint32_t lo = (uint32_t)d;
    return (uint32_t)(d >> 32) == 0 && lo - 1u < 0xffff0000u ? lo : 0;
}
#else
#define kept(s, seq) (seq)
#endif

/* What a received packet asks of the subscription, decoded and checked by `classify` */
enum { REPLY_LP_NACK = 1, REPLY_NACK, REPLY_SAMPLE };
typedef struct reply {
    /* words first: one load each from the stack on a Cortex-M0 */
    uint32_t kind, sync_name, has_nonce;
    ln_pull_seq seq;             /* 0 for /<name>/sync (or unknown: kept) */
    ln_pull_seq latest;          /* content.latest_seq, kept */
    uint32_t nonce;              /* REPLY_LP_NACK, if has_nonce */
    ln_ndn_pull_content content; /* REPLY_NACK, REPLY_SAMPLE */
} reply;

/* 1 if the packet is a reply to this subscription (*out says what it asks), 0 if it is for
 * another name, or an error (LN_NDN_ESIGNATURE: it did not verify).  Inlined: on a
 * Cortex-M0+ the one frame is smaller than the two, in stack as in code (docs/pull.md). */
static int classify(ln_pull_sub* s, const uint8_t* packet, size_t size, reply* out)
{
    ln_ndn_i_reply p;
    ln_ndn_bytes rest;
    ln_ndn_component c;
    uint64_t seq = 0;
    int r;
    if ((r = ln_ndn_i_decode_reply(packet, size, &p)) < 0)
        return r;
    if (p.type == LN_NDN_T_INTEREST && !p.lp_nack)
        return LN_NDN_EUNSUPPORTED;
    /* s->name is whole components (checked at start): a byte prefix is a name prefix */
    if (p.name.size < s->name_size || ln_ndn_i_differ(p.name.data, s->name, s->name_size))
        return 0;
    rest.data = p.name.data + s->name_size;
    rest.size = p.name.size - s->name_size;
    /* /<name>/seq=<s>, /<name>/sync (the Interest) or /<name>/sync/seq=<L> (its Data) */
    if (ln_ndn_i_component(&rest, &c) != 1)
        return 0;
    out->sync_name = c.type == LN_NDN_T_GENERIC && c.value.size == 4 &&
                     !ln_ndn_i_differ(c.value.data, "sync", 4);
    if (out->sync_name && p.type == LN_NDN_T_DATA && ln_ndn_i_component(&rest, &c) != 1)
        return 0;
    if (!out->sync_name || p.type == LN_NDN_T_DATA) {
        if (c.type != LN_NDN_T_SEQUENCE_NUM)
            return 0;
        if ((r = ln_ndn_i_nonneg(&c.value, &seq)) < 0)
            return r;
    }
    if (rest.size) /* longer than any name of ours */
        return 0;
    out->seq = kept(s, seq);
    if (p.type == LN_NDN_T_INTEREST) { /* an NDNLPv2 Nack of one of our Interests */
        out->kind = REPLY_LP_NACK;
        out->nonce = p.nonce;
        out->has_nonce = p.has_nonce;
        return 1;
    }
#ifdef VERIFY
    if (s->key && !verified(s, &p))
        return LN_NDN_ESIGNATURE;
#endif
    if ((r = ln_ndn_i_decode_content(&p.content, &out->content)) < 0)
        return r;
    if (p.content_type == LN_NDN_CONTENT_NACK)
        out->kind = REPLY_NACK;
    else if (p.content_type == LN_NDN_CONTENT_BLOB && seq)
        out->kind = REPLY_SAMPLE;
    else
        return LN_NDN_EUNSUPPORTED;
#ifdef LN_NDN_CONSUMER
    if (!out->seq && out->sync_name && s->syncing && out->kind == REPLY_SAMPLE) {
        s->seq_base = seq - 1; /* seq is kept as 1 from now on */
        s->delivered_seq = 0;
        ln_ndn_i_zero(s->slots, sizeof s->slots);
        out->seq = 1;
    }
#endif
    out->latest = kept(s, out->content.latest_seq);
    return 1;
}

LN_NDN_EXPORT int ln_pull_receive(ln_pull_sub* s, const uint8_t* packet, size_t size,
                                  uint32_t now_ms)
{
    reply q;
    int r;
    if (!s || (!packet && size))
        return LN_NDN_EINVAL;
    if ((r = classify(s, packet, size, &q)) < 0) {
        if (r == LN_NDN_ESIGNATURE)
            s->stats.rejected++;
        else
            s->stats.bad++;
    }
    if (r <= 0)
        return r;
    if (q.kind == REPLY_LP_NACK) {
        ln_pull_slot* slot = q.sync_name ? NULL : find(s, q.seq);
        uint32_t n = q.sync_name ? s->sync_nonce : slot ? slot->nonce : 0;
        if ((q.sync_name && !s->syncing) || (!q.sync_name && !slot) || !q.has_nonce ||
            q.nonce != n) { /* a Nack names the Interest it answers */
            s->stats.late++;
            return 1;
        }
        s->stats.nacks++;
        event(s, LN_PULL_EV_NACK, q.seq);
        if ((s->opt.flags & LN_PULL_NACK_JUMP) && !POLL_MS(s)) /* a fast failure */
            on_timeout(s, slot, now_ms);
    } else if (q.kind == REPLY_NACK) {
        on_nack(s, q.sync_name ? 0 : q.seq, q.latest, now_ms);
    } else {
        on_sample(s, q.seq, q.latest, &q.content, now_ms, q.sync_name);
    }
    return 1;
}

/* ---- timers --------------------------------------------------------------------------------- */
/* The ms until the next timeout is due (0: one has expired).  While a sync is pending, its
 * timeout (*expired NULL); else the next slot's deadline (BIG_MS: none pending) and in
 * *expired the slot of the oldest seq among those whose deadline has passed (NULL: none). */
static uint32_t scan(ln_pull_sub* s, uint32_t now, ln_pull_slot** expired)
{
    uint32_t next = BIG_MS, d;
    int i;
    *expired = NULL;
    if (s->syncing)
        return until(now, s->sync_sent_ms + s->t_ms);
    for (i = 0; i < LN_PULL_MAX_WINDOW; i++) {
        ln_pull_slot* slot = &s->slots[i];
        if (!slot->seq)
            continue;
        d = until(now, deadline(s, slot));
        if (d < next)
            next = d;
        if (!d && (!*expired || slot->seq < (*expired)->seq))
            *expired = slot;
    }
    return next;
}

LN_NDN_EXPORT uint32_t ln_pull_poll(ln_pull_sub* s, uint32_t now_ms)
{
    ln_pull_slot* expired;
    if (!s || !s->send)
        return BIG_MS;
#ifndef LN_NDN_CONSUMER
    if (s->opt.poll_ms) { /* fixed rate: one /sync every poll_ms */
        uint32_t due = s->sync_sent_ms + s->opt.poll_ms;
        if (until(now_ms, due) == 0) {
            if (s->syncing) {
                s->stats.timeouts++;
                event(s, LN_PULL_EV_TIMEOUT, 0);
            }
            sync(s, (uint32_t)(now_ms - due) < s->opt.poll_ms ? due : now_ms);
        }
        return until(now_ms, s->sync_sent_ms + s->opt.poll_ms);
    }
#endif
    /* the sync, or the oldest expired slot first, with t as it is then (a new sync is due
     * t >= 1 ms later: the loop ends) */
    while (scan(s, now_ms, &expired) == 0)
        on_timeout(s, expired, now_ms);
    fill(s, now_ms);
    return scan(s, now_ms, &expired);
}
