/* pull_dit.c — the pull-topic consumer (ln/pull.h): Dynamic Interest Timeout as
 * dit_transport §1.3 defines it (flags 0, window 1, boot_after 1), the hardenings of §5.4
 * as options, and a fixed-rate polling baseline (poll_ms > 0).  No malloc, no system calls:
 * the caller passes the clock in ms (uint32, wrap-safe), a send function and the packets it
 * received.  docs/pull.md has the rules and formulas.  Interests are written here directly;
 * with -DLN_NDN_CONSUMER (a device's build) replies are decoded here too (decode below). */
#include <string.h>

#include "ln/pull.h"
#include "ndn_internal.h"

#define BIG_MS 0x7fffffffu

LN_NDN_EXPORT void ln_pull_options_naive(ln_pull_options* o)
{
    memset(o, 0, sizeof *o);
    o->t_min_ms = 10;
    o->t_max_ms = 2000;
    o->window = 1;
    o->boot_after = 1;
}

LN_NDN_EXPORT void ln_pull_options_hardened(ln_pull_options* o, uint32_t deadline_ms)
{
    memset(o, 0, sizeof *o);
    o->t_max_ms = deadline_ms;
    o->t_min_ms = deadline_ms < 10 ? deadline_ms : 10;
    o->window = 3;
    o->boot_after = 3;
    o->flags = LN_PULL_SLOT_OFFSET | LN_PULL_SKIP_OLD | LN_PULL_NACK_JUMP | LN_PULL_SYNC_QUARTER |
               LN_PULL_KARN | LN_PULL_SYNC_SLOTS | LN_PULL_REFRESH | LN_PULL_AUTO_WINDOW;
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

static void event(ln_pull_sub* s, int ev, uint64_t seq)
{
    if (s->on_event)
        s->on_event(s->user, ev, seq, s->t_ms);
}

/* Sends an Interest for /<name>/seq=<seq>, or for /<name>/sync when seq is 0: the bytes
 * ln_ndn_encode_interest would write, written here directly (every length fits one byte:
 * the name is at most LN_PULL_MAX_NAME bytes, the Interest at most LN_PULL_TX_BYTES < 253),
 * which keeps the generic encoder out of a device's consumer. */
/* A TLV of `type` holding v big-endian in the fewest of 1, 2, 4, 8 bytes (at least `min`). */
static uint8_t* put_number(uint8_t* p, uint8_t type, uint64_t v, uint8_t min)
{
    uint8_t len = min, i;
    while (len < 8 && v >> (8 * len))
        len *= 2;
    *p++ = type;
    *p++ = len;
    for (i = len; i > 0; i--, v >>= 8)
        p[i - 1] = (uint8_t)v;
    return p + len;
}

static void send_interest(ln_pull_sub* s, uint64_t seq, uint32_t n, uint32_t lifetime)
{
    uint8_t packet[LN_PULL_TX_BYTES], *p = packet + 4;
    memcpy(p, s->name, s->name_size);
    p += s->name_size;
    if (seq) { /* SequenceNum component: a NonNegativeInteger of 1, 2, 4 or 8 bytes */
        p = put_number(p, LN_NDN_T_SEQUENCE_NUM, seq, 1);
    } else {
        memcpy(p, "\x08\x04sync", 6);
        p += 6;
    }
    packet[2] = LN_NDN_T_NAME;
    packet[3] = (uint8_t)(p - packet - 4);
    if (!seq) { /* CanBePrefix, MustBeFresh */
        memcpy(p, "\x21\x00\x12\x00", 4);
        p += 4;
    }
    p = put_number(p, LN_NDN_T_NONCE, n, 4);
    if (lifetime != LN_NDN_DEFAULT_LIFETIME_MS)
        p = put_number(p, LN_NDN_T_INTEREST_LIFETIME, lifetime, 1);
    packet[0] = LN_NDN_T_INTEREST;
    packet[1] = (uint8_t)(p - packet - 2);
    s->stats.interests++;
    if (!seq)
        s->stats.syncs++;
    s->send(s->user, packet, (size_t)(p - packet));
}

/* P̂ in ms, rounded */
static uint32_t period_ms(const ln_pull_sub* s)
{
    return s->period_ewma_us / 1000 + (s->period_ewma_us % 1000 >= 500);
}

/* The timeout of the Interest pending for `seq`: t, plus (j-1)·P̂ with SLOT_OFFSET, j being
 * seq's distance from the newest delivered sample (1..window in effect). */
static uint32_t slot_timeout(const ln_pull_sub* s, uint64_t seq)
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

static ln_pull_slot* find(ln_pull_sub* s, uint64_t seq)
{
    int i;
    for (i = 0; i < LN_PULL_MAX_WINDOW; i++)
        if (seq && s->slots[i].seq == seq)
            return &s->slots[i];
    return NULL;
}

static void take(ln_pull_sub* s, ln_pull_slot* slot, uint64_t seq, uint32_t now)
{
    slot->seq = seq;
    slot->sent_ms = now;
    slot->nonce = nonce(s);
    slot->retries = 0;
    slot->flags = seq <= s->latest_seq ? 2 : 0; /* published already: its reply is an RTT */
    send_interest(s, seq, slot->nonce, slot_timeout(s, seq));
}

/* Puts an Interest for the next seqs into free slots until `window` are pending (never a
 * seq already pending).  A slot beyond a shrunk window runs out but is not refilled. */
static void fill(ln_pull_sub* s, uint32_t now)
{
    int i, used = 0;
    if ((s->syncing && !(s->opt.flags & LN_PULL_SYNC_SLOTS)) || s->opt.poll_ms)
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
    memset(s->slots, 0, sizeof s->slots);
    s->syncing = 1;
    s->sync_sent_ms = now;
    s->sync_nonce = nonce(s);
    send_interest(s, 0, s->sync_nonce, s->opt.poll_ms ? s->opt.poll_ms : s->t_ms);
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
        w += s->srtt_us / p + (s->srtt_us % p != 0);
        if (w > LN_PULL_MAX_WINDOW)
            w = LN_PULL_MAX_WINDOW;
    }
    s->window = (uint8_t)w;
}

/* An RTT sample (RFC 6298 SRTT, gain 1/8), from the immediate reply to a sync or to an
 * Interest for a seq published when it was sent, or a parked one's Δ below SRTT (an upper
 * bound of the RTT: SRTT can come down); never from a resent or refreshed one (Karn). */
static void rtt_sample(ln_pull_sub* s, uint32_t sent, uint32_t now)
{
    uint32_t r = (uint32_t)(now - sent) > 4000000u ? 4000000000u : (now - sent) * 1000u;
    s->srtt_us = !s->srtt_us       ? r
                 : r >= s->srtt_us ? s->srtt_us + (r - s->srtt_us) / 8
                                   : s->srtt_us - (s->srtt_us - r) / 8;
    size_window(s);
}

static void halve_if_quick(ln_pull_sub* s, uint32_t sent, uint32_t now)
{
    if ((uint64_t)(uint32_t)(now - sent) * 4 < s->t_ms) {
        s->t_ms /= 2;
        if (s->t_ms < s->opt.t_min_ms)
            s->t_ms = s->opt.t_min_ms;
    }
}

static void double_t(ln_pull_sub* s)
{
    s->t_ms = s->t_ms > s->opt.t_max_ms / 2 ? s->opt.t_max_ms : s->t_ms * 2;
}

static void deliver(ln_pull_sub* s, uint64_t seq, const ln_ndn_pull_content* c, uint32_t now)
{
    if (s->since_loss < 255)
        s->since_loss++;
    if (s->delivered_seq && seq > s->delivered_seq + 1) /* a seq skipped: lost (or jumped) */
        s->since_loss = 0;
    if (s->delivered_seq && seq > s->delivered_seq) { /* P̂: EWMA (1/8) of the period */
        /* in 32 bits (no 64-bit division on small cores): gaps capped at 4e6 ms, 65535 seqs */
        uint32_t gap = now - s->last_arrival_ms, n = seq - s->delivered_seq > 0xffffu
                                                         ? 0xffffu
                                                         : (uint32_t)(seq - s->delivered_seq);
        uint32_t sample = (gap > 4000000u ? 4000000u : gap) * 1000u / n, p = s->period_ewma_us;
        s->period_ewma_us = !p ? sample : sample >= p ? p + (sample - p) / 8 : p - (p - sample) / 8;
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
        s->on_data(s->user, seq, c->payload.data, c->payload.size, c->publish_us);
}

static void on_timeout(ln_pull_sub* s, ln_pull_slot* slot, uint32_t now)
{
    uint64_t seq = slot ? slot->seq : 0;
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
        slot->sent_ms = now;
        slot->nonce = nonce(s);
        if (slot->retries < 255)
            slot->retries++;
        send_interest(s, seq, slot->nonce, slot_timeout(s, seq));
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
    if (!s || !name || !o || !send || o->t_min_ms < 1 || o->t_min_ms > o->t_max_ms ||
        o->t_max_ms > BIG_MS || o->window < 1 || o->window > LN_PULL_MAX_WINDOW ||
        o->boot_after < 1 || o->poll_ms > BIG_MS)
        return LN_NDN_EINVAL;
    if (size == 0)
        return LN_NDN_ENAME;
    if (size > LN_PULL_MAX_NAME)
        return LN_NDN_ESPACE;
    rest.data = name;
    rest.size = size;
    while ((r = ln_ndn_name_next(&rest, &c)) > 0)
        ;
    if (r < 0)
        return LN_NDN_ENAME;
    memset(s, 0, sizeof *s);
    memcpy(s->name, name, size);
    s->name_size = (uint16_t)size;
    s->opt = *o;
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
static void on_sync_reply(ln_pull_sub* s, uint64_t seq, const ln_ndn_pull_content* c, uint32_t now)
{
    if (s->opt.poll_ms) { /* polling: every reply counts, the newest sample is delivered */
        s->syncing = 0;
        s->latest_seq = c->latest_seq ? c->latest_seq : seq;
        if (seq > s->delivered_seq)
            deliver(s, seq, c, now);
        else if (seq < s->delivered_seq)
            s->stats.late++;
        return;
    }
    if (!s->syncing) {
        s->stats.late++;
        return;
    }
    if (s->opt.flags & LN_PULL_SYNC_QUARTER)
        halve_if_quick(s, s->sync_sent_ms, now);
    if (s->opt.flags & LN_PULL_AUTO_WINDOW)
        rtt_sample(s, s->sync_sent_ms, now);
    s->syncing = 0;
    s->timeouts_in_row = 0;
    s->latest_seq = c->latest_seq ? c->latest_seq : seq;
    if (!s->period_ewma_us && c->period_us) /* P̂ starts from the producer's mean period */
        s->period_ewma_us = c->period_us > 0xffffffffu ? 0xffffffffu : (uint32_t)c->period_us;
    if (seq != s->delivered_seq) /* below it: the producer started over */
        deliver(s, seq, c, now);
    s->next_seq = seq + 1;
    fill(s, now);
}

static void on_sample(ln_pull_sub* s, uint64_t seq, const ln_ndn_pull_content* c, uint32_t now)
{
    ln_pull_slot* slot = find(s, seq);
    if (!slot) {
        s->stats.late++;
        return;
    }
    int i;
    if (!((s->opt.flags & LN_PULL_KARN) && slot->retries))
        halve_if_quick(s, slot->sent_ms, now);
    /* Δ is an RTT for a published seq, and at least one for a parked one: that lowers SRTT */
    if ((s->opt.flags & LN_PULL_AUTO_WINDOW) && !(slot->flags & 1) && !slot->retries &&
        (slot->flags || (uint32_t)(now - slot->sent_ms) * 1000u < s->srtt_us))
        rtt_sample(s, slot->sent_ms, now);
    s->timeouts_in_row = 0;
    s->syncing = 0; /* a sample ends a re-bootstrap too (SYNC_SLOTS) */
    s->latest_seq = c->latest_seq ? c->latest_seq : seq;
    slot->seq = 0;
    if (seq > s->delivered_seq)
        deliver(s, seq, c, now);
    else
        s->stats.late++;
    if ((s->opt.flags & LN_PULL_NACK_JUMP) && c->latest_seq > seq && s->next_seq < c->latest_seq)
        s->next_seq = c->latest_seq; /* behind: go straight to the newest */
    /* REFRESH (while a loss was seen in the last LN_PULL_REFRESH_SPAN samples): an Interest
     * pending for at least P̂/2, not yet resent, for a seq that is not published before a
     * new Interest could get there ((seq - newest)·P̂ > SRTT), goes out once more (new
     * nonce): a lost Interest is recovered before its sample is published */
    for (i = 0; (s->opt.flags & LN_PULL_REFRESH) && s->since_loss < LN_PULL_REFRESH_SPAN &&
                i < LN_PULL_MAX_WINDOW;
         i++) {
        ln_pull_slot* r = &s->slots[i];
        if (r->seq > s->delivered_seq && !r->retries && !(r->flags & 1) &&
            (uint32_t)(now - r->sent_ms) * 2000u >= s->period_ewma_us &&
            (r->seq - s->delivered_seq) * s->period_ewma_us > s->srtt_us) {
            r->flags |= 1;
            r->sent_ms = now;
            r->nonce = nonce(s);
            s->stats.refreshes++;
            send_interest(s, r->seq, r->nonce, slot_timeout(s, r->seq));
        }
    }
    fill(s, now);
}

static void on_nack(ln_pull_sub* s, uint64_t seq, uint64_t latest, uint32_t now)
{
    ln_pull_slot* slot = find(s, seq);
    s->stats.nacks++;
    event(s, LN_PULL_EV_NACK, seq);
    if (seq == 0) { /* sync refused (nothing published yet): its timer runs on, or next poll */
        if (s->opt.poll_ms)
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

#ifdef LN_NDN_CONSUMER
/* A device's consumer-only build decodes replies with this compact equivalent of
 * ln_ndn_decode (same acceptance rules, same nesting bound, no callbacks): the LpPacket
 * headers, then a Data packet (Name, MetaInfo, Content, SignatureInfo with its type,
 * SignatureValue: the signature itself is not verified, as in the full build) or the Name
 * and Nonce of an Interest (what an NDNLPv2 Nack carries). */

/* A TLV type in 32 bits (no 64-bit compares on small cores): one above 2^32 becomes one
 * that is no known type and critical exactly when it is (odd). */
static uint32_t type32(uint64_t type)
{
    return type > 0xffffffffu ? 0xfffffffeu | (uint32_t)(type & 1u) : (uint32_t)type;
}

/* The elements of `v` in the grammar's order `order[n]` into f[n] (absent: data NULL); one
 * out of order or unknown follows the evolvability rule. */
static int fields(ln_ndn_bytes v, const uint8_t* order, size_t n, ln_ndn_bytes* f)
{
    ln_ndn_i_tlv t;
    size_t next = 0, i;
    uint32_t type;
    int r;
    memset(f, 0, n * sizeof *f);
    while ((r = ln_ndn_i_next(&v, &t)) > 0) {
        type = type32(t.type);
        for (i = next; i < n && order[i] != type; i++) {
        }
        if (i == n) {
            if (type < 32 || (type & 1u))
                return LN_NDN_ECRITICAL;
            continue;
        }
        next = i + 1;
        f[i] = t.value;
    }
    return r;
}

/* A name value of at least `min` components (each a TLV of a type in 1..65535). */
static int check_name(ln_ndn_bytes name, int min)
{
    ln_ndn_component c;
    int r;
    while ((r = ln_ndn_name_next(&name, &c)) > 0)
        min--;
    return r < 0 ? r : min > 0 ? LN_NDN_EMALFORMED : LN_NDN_OK;
}

/* A NonNegativeInteger, clamped to 32 bits. */
static int nonneg32(ln_ndn_bytes v, uint32_t* out)
{
    uint64_t x;
    int r = ln_ndn_read_nonneg(v, &x);
    *out = x > 0xffffffffu ? 0xffffffffu : (uint32_t)x;
    return r;
}

static int decode(const uint8_t* buf, size_t size, ln_ndn_packet* out)
{
    static const uint8_t interest_order[] = {LN_NDN_T_NAME,
                                             LN_NDN_T_CAN_BE_PREFIX,
                                             LN_NDN_T_MUST_BE_FRESH,
                                             LN_NDN_T_FORWARDING_HINT,
                                             LN_NDN_T_NONCE,
                                             LN_NDN_T_INTEREST_LIFETIME,
                                             LN_NDN_T_HOP_LIMIT,
                                             LN_NDN_T_APP_PARAMETERS,
                                             0x2c,
                                             0x2e};
    static const uint8_t data_order[] = {LN_NDN_T_NAME,
                                         LN_NDN_T_META_INFO,
                                         LN_NDN_T_CONTENT,
                                         LN_NDN_T_SIGNATURE_INFO,
                                         LN_NDN_T_SIGNATURE_VALUE,
                                         LN_NDN_T_CONTENT_TYPE,
                                         LN_NDN_T_FRESHNESS_PERIOD,
                                         LN_NDN_T_FINAL_BLOCK_ID,
                                         LN_NDN_T_SIGNATURE_TYPE,
                                         LN_NDN_T_KEY_LOCATOR};
    ln_ndn_bytes rest, f[10], sub;
    ln_ndn_i_tlv t, n;
    ln_ndn_component c;
    uint32_t v, ty;
    int r, lp = 0, nack = 0;
    memset(out, 0, sizeof *out);
    rest.data = buf;
    rest.size = size;
    for (;;) { /* one LpPacket level per turn (ln_ndn_decode's depth: 2 per level) */
        if ((r = ln_ndn_i_next(&rest, &t)) <= 0)
            return r < 0 ? r : LN_NDN_ETRUNCATED;
        if (rest.size != 0)
            return LN_NDN_EMALFORMED;
        if ((ty = type32(t.type)) != LN_NDN_T_LP_PACKET)
            break;
        lp++;
        rest.size = 0;
        sub = t.value;
        while ((r = ln_ndn_i_next(&sub, &t)) > 0) {
            ty = type32(t.type);
            if (rest.size) /* nothing may follow the fragment */
                return LN_NDN_EMALFORMED;
            if (ty == LN_NDN_T_LP_FRAGMENT) {
                rest = t.value;
                if (!rest.size)
                    return LN_NDN_EMALFORMED;
            } else if (ty == LN_NDN_T_LP_PIT_TOKEN) {
                if (t.value.size < 1 || t.value.size > 32)
                    return LN_NDN_EMALFORMED;
            } else if (ty == LN_NDN_T_LP_NACK) {
                nack = 1;
                while ((r = ln_ndn_i_next(&t.value, &n)) > 0) {
                    if (type32(n.type) == LN_NDN_T_LP_NACK_REASON) {
                        if ((r = nonneg32(n.value, &v)) < 0)
                            return r;
                    } else if (ln_ndn_i_critical(n.type)) {
                        return LN_NDN_ECRITICAL;
                    }
                }
                if (r < 0)
                    return r;
            } else if (ty == 0x52 || ty == 0x53) { /* FragIndex 0, FragCount 1 only */
                if ((r = nonneg32(t.value, &v)) < 0)
                    return r;
                if (v != (ty == 0x53))
                    return LN_NDN_EUNSUPPORTED;
            } else if (ty != 0x51 && /* Sequence; else only ignorable LP headers */
                       !(ty >= 800 && ty <= 959 && (ty & 3u) == 0)) {
                return LN_NDN_ECRITICAL;
            }
        }
        if (r < 0)
            return r;
        if (!rest.size) /* an IDLE packet */
            return LN_NDN_EUNSUPPORTED;
        if (lp == 4) /* the packet in the fourth LpPacket is nested too deep */
            return LN_NDN_EDEPTH;
    }
    if (ty == LN_NDN_T_INTEREST) {
        out->type = LN_NDN_T_INTEREST;
        if ((r = fields(t.value, interest_order, 10, f)) < 0 ||
            (f[0].data && (r = check_name(f[0], 1)) < 0))
            return r;
        if (f[4].data) {
            if (f[4].size != 4)
                return LN_NDN_EMALFORMED;
            out->interest.nonce = (uint32_t)f[4].data[0] << 24 | (uint32_t)f[4].data[1] << 16 |
                                  (uint32_t)f[4].data[2] << 8 | f[4].data[3];
            out->interest.has_nonce = 1;
        }
        if (!f[0].data)
            return LN_NDN_EMALFORMED;
        out->interest.name = f[0];
        out->lp_nack = (uint8_t)nack;
        return LN_NDN_OK;
    }
    if (ty != LN_NDN_T_DATA)
        return LN_NDN_EUNSUPPORTED;
    if (nack)
        return LN_NDN_EMALFORMED;
    out->type = LN_NDN_T_DATA;
    if ((r = fields(t.value, data_order, 5, f)) < 0 || (f[0].data && (r = check_name(f[0], 0)) < 0))
        return r;
    if (f[1].data) { /* MetaInfo */
        if (lp == 3)
            return LN_NDN_EDEPTH;
        if ((r = fields(f[1], data_order + 5, 3, f + 5)) < 0 ||
            (f[5].data && (r = nonneg32(f[5], &out->data.content_type)) < 0) ||
            (f[6].data && (r = nonneg32(f[6], &v)) < 0))
            return r;
        if (f[7].data) { /* FinalBlockId: exactly one name component */
            if ((r = ln_ndn_name_next(&f[7], &c)) < 0)
                return r;
            if (r != 1 || f[7].size)
                return LN_NDN_EMALFORMED;
        }
    }
    if (!f[3].data || !f[0].data || !f[4].data) /* SignatureInfo, Name, SignatureValue */
        return LN_NDN_EMALFORMED;
    if (lp == 3)
        return LN_NDN_EDEPTH;
    if ((r = fields(f[3], data_order + 8, 2, f + 8)) < 0 ||
        (f[8].data && (r = nonneg32(f[8], &v)) < 0))
        return r;
    if (!f[8].data) /* SignatureType */
        return LN_NDN_EMALFORMED;
    out->data.name = f[0];
    out->data.content = f[2];
    return LN_NDN_OK;
}
#else
#define decode ln_ndn_decode
#endif

LN_NDN_EXPORT int ln_pull_receive(ln_pull_sub* s, const uint8_t* packet, size_t size,
                                  uint32_t now_ms)
{
    ln_ndn_packet p;
    ln_ndn_bytes name, rest;
    ln_ndn_component c;
    ln_ndn_pull_content content;
    uint64_t seq = 0;
    int sync_name = 0, r;
    if (!s || (!packet && size))
        return LN_NDN_EINVAL;
    if ((r = decode(packet, size, &p)) < 0)
        goto bad;
    if (p.type == LN_NDN_T_INTEREST && !p.lp_nack) {
        r = LN_NDN_EUNSUPPORTED;
        goto bad;
    }
    name = p.type == LN_NDN_T_DATA ? p.data.name : p.interest.name;
    /* s->name is whole components (checked at start): a byte prefix is a name prefix */
    if (name.size < s->name_size || memcmp(name.data, s->name, s->name_size) != 0)
        return 0;
    rest.data = name.data + s->name_size;
    rest.size = name.size - s->name_size;
    /* /<name>/seq=<s>, /<name>/sync (the Interest) or /<name>/sync/seq=<L> (its Data) */
    if (ln_ndn_name_next(&rest, &c) != 1)
        return 0;
    if (c.type == LN_NDN_T_GENERIC && c.value.size == 4 && memcmp(c.value.data, "sync", 4) == 0) {
        sync_name = 1;
        if (p.type == LN_NDN_T_DATA && ln_ndn_name_next(&rest, &c) != 1)
            return 0;
    }
    if (!sync_name || p.type == LN_NDN_T_DATA) {
        if (c.type != LN_NDN_T_SEQUENCE_NUM)
            return 0;
        if ((r = ln_ndn_read_nonneg(c.value, &seq)) < 0)
            goto bad;
    }
    if (rest.size) /* longer than any name of ours */
        return 0;
    if (p.type == LN_NDN_T_INTEREST) { /* an NDNLPv2 Nack of one of our Interests */
        ln_pull_slot* slot = sync_name ? NULL : find(s, seq);
        uint32_t n = sync_name ? s->sync_nonce : slot ? slot->nonce : 0;
        if ((sync_name && !s->syncing) || (!sync_name && !slot) ||
            (p.interest.has_nonce && p.interest.nonce != n)) {
            s->stats.late++;
            return 1;
        }
        s->stats.nacks++;
        event(s, LN_PULL_EV_NACK, seq);
        if ((s->opt.flags & LN_PULL_NACK_JUMP) && !s->opt.poll_ms) /* a fast failure */
            on_timeout(s, slot, now_ms);
        return 1;
    }
    if ((r = ln_ndn_decode_pull_content(p.data.content, &content)) < 0)
        goto bad;
    if (p.data.content_type == LN_NDN_CONTENT_NACK) {
        on_nack(s, sync_name ? 0 : seq, content.latest_seq, now_ms);
        return 1;
    }
    if (p.data.content_type != LN_NDN_CONTENT_BLOB || seq == 0) {
        r = LN_NDN_EUNSUPPORTED;
        goto bad;
    }
    if (sync_name)
        on_sync_reply(s, seq, &content, now_ms);
    else
        on_sample(s, seq, &content, now_ms);
    return 1;
bad:
    s->stats.bad++;
    return r;
}

/* ---- timers --------------------------------------------------------------------------------- */
LN_NDN_EXPORT uint32_t ln_pull_poll(ln_pull_sub* s, uint32_t now_ms)
{
    uint32_t next = BIG_MS, d;
    int i;
    if (!s || !s->send)
        return BIG_MS;
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
    if (s->syncing && until(now_ms, s->sync_sent_ms + s->t_ms) == 0)
        on_timeout(s, NULL, now_ms);
    while (!s->syncing) { /* the oldest expired slot first, with t as it is then */
        ln_pull_slot* expired = NULL;
        for (i = 0; i < LN_PULL_MAX_WINDOW; i++) {
            ln_pull_slot* slot = &s->slots[i];
            if (slot->seq && until(now_ms, deadline(s, slot)) == 0 &&
                (!expired || slot->seq < expired->seq))
                expired = slot;
        }
        if (!expired)
            break;
        on_timeout(s, expired, now_ms);
    }
    fill(s, now_ms);
    if (s->syncing)
        return until(now_ms, s->sync_sent_ms + s->t_ms);
    for (i = 0; i < LN_PULL_MAX_WINDOW; i++) {
        if (!s->slots[i].seq)
            continue;
        d = until(now_ms, deadline(s, &s->slots[i]));
        if (d < next)
            next = d;
    }
    return next;
}
