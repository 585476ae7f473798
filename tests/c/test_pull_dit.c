/* test_pull_dit.c — the pull consumer of libln_pull (ln/pull.h) with a fake clock and a
 * scripted producer: the exact sequence of DIT timeouts t for naive DIT (dit_transport
 * §1.3) and each hardening (§5.4), pipeline slots, re-bootstrap, NACKs, the latest-seq jump,
 * Karn's rule, the polling baseline, late Data, uint32 ms wrap-around and 64-bit seqs (a
 * device build keeps 32-bit offsets). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <ln/pull.h>

#include "ln_test.h"

#define TOPIC "/ln/robot/arm.state"

#ifdef LN_PULL_NO_URI
/* The device build (no URI parser in the consumer): the name is encoded here, as a device's
 * build does, and the same checks apply. */
static int start_uri(ln_pull_sub* s, const char* uri, const ln_pull_options* o,
                     ln_pull_send_fn send, ln_pull_data_fn on_data, ln_pull_event_fn on_event,
                     void* user, uint32_t now, uint32_t seed)
{
    uint8_t name[LN_PULL_MAX_NAME];
    int size = uri ? ln_ndn_name_from_uri(name, sizeof name, uri) : LN_NDN_EINVAL;
    return size < 0 ? size
                    : ln_pull_start_name(s, name, (size_t)size, o, send, on_data, on_event, user,
                                         now, seed);
}
#define ln_pull_start start_uri
#endif

/* ---- what the consumer sent, delivered and reported ---------------------------------------- */
typedef struct sent {
    int sync;
    uint64_t seq;
    uint32_t nonce, lifetime;
    int cbp, mbf;
} sent;
static sent tx[512];
static int ntx;
static uint64_t rx[512];
static int nrx;
static struct {
    int ev;
    uint64_t seq;
    uint32_t t;
} evs[512];
static int nev;
static uint8_t prefix[64];
static size_t prefix_size;

static void reset(void)
{
    ntx = nrx = nev = 0;
    prefix_size = (size_t)ln_ndn_name_from_uri(prefix, sizeof prefix, TOPIC);
}

static void on_send(void* user, const uint8_t* packet, size_t size)
{
    ln_ndn_packet p;
    ln_ndn_bytes rest;
    ln_ndn_component c;
    sent* s = &tx[ntx < 511 ? ntx++ : ntx];
    (void)user;
    memset(s, 0, sizeof *s);
    LN_CHECK(size <= LN_PULL_TX_BYTES);
    LN_CHECK_EQ(ln_ndn_decode(packet, size, &p), LN_NDN_OK);
    LN_CHECK_EQ(p.type, LN_NDN_T_INTEREST);
    LN_CHECK(p.interest.name.size > prefix_size &&
             memcmp(p.interest.name.data, prefix, prefix_size) == 0);
    rest.data = p.interest.name.data + prefix_size;
    rest.size = p.interest.name.size - prefix_size;
    LN_CHECK_EQ(ln_ndn_name_next(&rest, &c), 1);
    if (c.type == LN_NDN_T_GENERIC) {
        LN_CHECK(c.value.size == 4 && memcmp(c.value.data, "sync", 4) == 0);
        s->sync = 1;
    } else {
        LN_CHECK_EQ(c.type, LN_NDN_T_SEQUENCE_NUM);
        LN_CHECK_EQ(ln_ndn_read_nonneg(c.value, &s->seq), 0);
    }
    LN_CHECK_EQ(rest.size, 0);
    s->nonce = p.interest.nonce;
    s->lifetime = p.interest.lifetime_ms;
    s->cbp = p.interest.can_be_prefix;
    s->mbf = p.interest.must_be_fresh;
}

static void on_data(void* user, uint64_t seq, const uint8_t* payload, size_t size,
                    uint64_t publish_us)
{
    (void)user;
    LN_CHECK(size == 8 && payload && memcmp(payload, &seq, 8) == 0);
    LN_CHECK(publish_us == seq * 1000);
    if (nrx < 512)
        rx[nrx++] = seq;
}

static void on_event(void* user, int ev, uint64_t seq, uint32_t t)
{
    (void)user;
    if (nev < 512) {
        evs[nev].ev = ev;
        evs[nev].seq = seq;
        evs[nev].t = t;
        nev++;
    }
}

/* ---- a scripted producer ------------------------------------------------------------------ */
/* How reply() signs (NULL: DigestSha256), and whether it then flips a byte of the payload */
static const ln_ndn_signer* reply_signer;
static int reply_tampered;

/* Data /TOPIC/seq=<seq> (or /TOPIC/sync/seq=<seq>), payload = the seq's 8 bytes, header
 * latest; a NACK (ContentType 3, only the latest) when nack. */
static int reply(ln_pull_sub* s, uint32_t now, int sync, uint64_t seq, uint64_t latest, int nack)
{
    uint8_t name[96], content[64], out[256];
    ln_ndn_pull_content c;
    ln_ndn_data d;
    ln_ndn_signer sig = {LN_NDN_SIG_DIGEST_SHA256, NULL, 0, {NULL, 0}};
    int n = ln_ndn_name_from_uri(name, sizeof name, TOPIC);
    if (sync)
        n = ln_ndn_name_append(name, sizeof name, (size_t)n, LN_NDN_T_GENERIC,
                               (const uint8_t*)"sync", 4);
    if (!(sync && nack))
        n = ln_ndn_name_append_seq(name, sizeof name, (size_t)n, seq);
    memset(&c, 0, sizeof c);
    c.latest_seq = latest;
    if (!nack) {
        c.publish_us = seq * 1000;
        c.period_us = 20000;
        c.payload.data = (const uint8_t*)&seq;
        c.payload.size = 8;
    }
    memset(&d, 0, sizeof d);
    d.name.data = name;
    d.name.size = (size_t)n;
    d.content.data = content;
    d.content.size = (size_t)ln_ndn_encode_pull_content(content, sizeof content, &c);
    d.content_type = nack ? LN_NDN_CONTENT_NACK : LN_NDN_CONTENT_BLOB;
    d.freshness_ms = nack || sync ? 0 : 1000;
    n = ln_ndn_encode_data(out, sizeof out, &d, reply_signer ? reply_signer : &sig);
    LN_CHECK(n > 40);
    if (reply_tampered) /* the payload's last byte: before SignatureInfo (5) and Value (34) */
        out[n - 40] ^= 1;
    return ln_pull_receive(s, out, (size_t)n, now);
}
#define DATA(s, now, seq, latest) LN_CHECK_EQ(reply(s, now, 0, seq, latest, 0), 1)
#define SYNC(s, now, seq) LN_CHECK_EQ(reply(s, now, 1, seq, seq, 0), 1)
#define NACK(s, now, seq, latest) LN_CHECK_EQ(reply(s, now, 0, seq, latest, 1), 1)

static void start(ln_pull_sub* s, const ln_pull_options* o, uint32_t now)
{
    reset();
    LN_CHECK_EQ(ln_pull_start(s, TOPIC, o, on_send, on_data, on_event, NULL, now, 7), LN_NDN_OK);
}

/* every pending seq distinct and non-zero where taken */
static void check_slots(const ln_pull_sub* s)
{
    for (int i = 0; i < LN_PULL_MAX_WINDOW; i++)
        for (int j = i + 1; j < LN_PULL_MAX_WINDOW; j++)
            LN_CHECK(!s->slots[i].seq || s->slots[i].seq != s->slots[j].seq);
}

static int pending(const ln_pull_sub* s, uint64_t seq)
{
    for (int i = 0; i < s->opt.window; i++)
        if (s->slots[i].seq == seq)
            return 1;
    return 0;
}

/* ---- naive DIT (§1.3) ------------------------------------------------------------------------ */
static void test_naive_sequence(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    LN_CHECK(o.t_min_ms == 10 && o.t_max_ms == 2000 && o.window == 1 && o.boot_after == 1 &&
             o.flags == 0 && o.poll_ms == 0);
    start(&s, &o, 0);
    /* init: t = t_max, a sync Interest with CanBePrefix + MustBeFresh, lifetime t */
    LN_CHECK_EQ(ntx, 1);
    LN_CHECK(tx[0].sync && tx[0].cbp && tx[0].mbf && tx[0].lifetime == 2000);
    LN_CHECK_EQ(s.t_ms, 2000);
    LN_CHECK_EQ(ln_pull_poll(&s, 0), 2000);
    /* sync Data L = 10 after 100 ms: delivered, no t/4 rule on it, /seq=11 with lifetime t */
    SYNC(&s, 100, 10);
    LN_CHECK(nrx == 1 && rx[0] == 10);
    LN_CHECK_EQ(s.t_ms, 2000);
    LN_CHECK(ntx == 2 && !tx[1].sync && tx[1].seq == 11 && tx[1].lifetime == 2000 && !tx[1].cbp &&
             !tx[1].mbf);
    /* replies 50 ms after each Interest: t halves while 50 < t/4: 1000 500 250 125, then stays */
    static const uint32_t want_t[] = {1000, 500, 250, 125, 125, 125};
    uint32_t now = 100;
    for (int i = 0; i < 6; i++) {
        now += 50;
        DATA(&s, now, 11 + (uint64_t)i, 11 + (uint64_t)i);
        LN_CHECK_EQ(s.t_ms, want_t[i]);
        LN_CHECK(tx[ntx - 1].seq == 12 + (uint64_t)i && tx[ntx - 1].lifetime == want_t[i]);
    }
    LN_CHECK_EQ(nrx, 7);
    LN_CHECK_EQ(s.stats.data, 7);
    /* Δ exactly t/4 does not halve (125/4 = 31.25: Δ = 31 halves, 32 does not) */
    now += 32;
    DATA(&s, now, 17, 17);
    LN_CHECK_EQ(s.t_ms, 125);
    /* now /seq=18 is pending since `now`; no reply: a timeout at now + 125 exactly */
    LN_CHECK_EQ(ln_pull_poll(&s, now + 124), 1);
    int before = ntx;
    LN_CHECK_EQ(ln_pull_poll(&s, now + 125), 250);
    /* every timeout doubles t (capped at t_max) and re-bootstraps (N_boot = 1) */
    LN_CHECK_EQ(s.t_ms, 250);
    LN_CHECK(ntx == before + 1 && tx[before].sync && tx[before].lifetime == 250);
    now += 125;
    static const uint32_t want_sync_t[] = {500, 1000, 2000, 2000, 2000};
    for (int i = 0; i < 5; i++) {
        now += s.t_ms;
        ln_pull_poll(&s, now);
        LN_CHECK_EQ(s.t_ms, want_sync_t[i]);
        LN_CHECK(tx[ntx - 1].sync && tx[ntx - 1].lifetime == want_sync_t[i]);
    }
    /* the events: TIMEOUT then SYNC for each, with t after doubling */
    int timeouts = 0, syncs = 0;
    uint32_t last_t = 0;
    for (int i = 0; i < nev; i++) {
        if (evs[i].ev == LN_PULL_EV_TIMEOUT) {
            timeouts++;
            LN_CHECK(evs[i].t >= last_t);
            last_t = evs[i].t;
        }
        syncs += evs[i].ev == LN_PULL_EV_SYNC;
    }
    LN_CHECK_EQ(timeouts, 6);
    LN_CHECK_EQ(syncs, 7); /* the first one at start */
    LN_CHECK_EQ(s.stats.timeouts, 6);
    LN_CHECK_EQ(s.stats.syncs, 7);
    LN_CHECK_EQ(s.stats.interests, (uint32_t)ntx);
    /* a sync reply after all that: delivered, the pipeline restarts after it */
    SYNC(&s, now + 5, 40);
    LN_CHECK(rx[nrx - 1] == 40 && tx[ntx - 1].seq == 41);
    LN_CHECK_EQ(s.timeouts_in_row, 0);
}

static void test_floor_and_cap(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.t_min_ms = 15;
    start(&s, &o, 1000);
    SYNC(&s, 1000, 1);
    /* instant replies: 2000 1000 500 250 125 62 31 15 15 ... (integer halving, floor 15) */
    static const uint32_t want[] = {1000, 500, 250, 125, 62, 31, 15, 15, 15};
    for (int i = 0; i < 9; i++) {
        DATA(&s, 1000, 2 + (uint64_t)i, 2 + (uint64_t)i);
        LN_CHECK_EQ(s.t_ms, want[i]);
    }
    /* cap: 15 30 60 120 240 480 960 1920 2000 2000 */
    static const uint32_t up[] = {30, 60, 120, 240, 480, 960, 1920, 2000, 2000};
    uint32_t now = 1000;
    for (int i = 0; i < 9; i++) {
        now += s.t_ms;
        ln_pull_poll(&s, now);
        LN_CHECK_EQ(s.t_ms, up[i]);
    }
    /* bad options */
    ln_pull_options bad = o;
    bad.t_min_ms = 0;
    LN_CHECK_EQ(ln_pull_start(&s, TOPIC, &bad, on_send, NULL, NULL, NULL, 0, 1), LN_NDN_EINVAL);
    bad = o;
    bad.t_min_ms = 3000;
    LN_CHECK_EQ(ln_pull_start(&s, TOPIC, &bad, on_send, NULL, NULL, NULL, 0, 1), LN_NDN_EINVAL);
    bad = o;
    bad.window = LN_PULL_MAX_WINDOW + 1;
    LN_CHECK_EQ(ln_pull_start(&s, TOPIC, &bad, on_send, NULL, NULL, NULL, 0, 1), LN_NDN_EINVAL);
    bad = o;
    bad.boot_after = 0;
    LN_CHECK_EQ(ln_pull_start(&s, TOPIC, &bad, on_send, NULL, NULL, NULL, 0, 1), LN_NDN_EINVAL);
    LN_CHECK_EQ(ln_pull_start(&s, TOPIC, &o, NULL, NULL, NULL, NULL, 0, 1), LN_NDN_EINVAL);
    LN_CHECK_EQ(ln_pull_start(&s, "no/slash", &o, on_send, NULL, NULL, NULL, 0, 1), LN_NDN_ENAME);
    LN_CHECK_EQ(ln_pull_start(&s, "/", &o, on_send, NULL, NULL, NULL, 0, 1), LN_NDN_ENAME);
    char long_uri[200];
    memset(long_uri, 'x', sizeof long_uri);
    long_uri[0] = '/';
    long_uri[sizeof long_uri - 1] = '\0';
    LN_CHECK_EQ(ln_pull_start(&s, long_uri, &o, on_send, NULL, NULL, NULL, 0, 1), LN_NDN_ESPACE);
}

/* ---- re-bootstrap after boot_after timeouts; retransmission with a new nonce -------------- */
static void test_reboot_after(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.boot_after = 3;
    o.t_max_ms = 100;
    start(&s, &o, 0);
    SYNC(&s, 0, 5); /* instant: no halving of a sync reply without SYNC_QUARTER */
    LN_CHECK_EQ(s.t_ms, 100);
    LN_CHECK(tx[1].seq == 6);
    ln_pull_poll(&s, 100); /* 1st timeout: t 100 (cap), retransmit /seq=6 */
    LN_CHECK(ntx == 3 && tx[2].seq == 6 && tx[2].nonce != tx[1].nonce);
    ln_pull_poll(&s, 200); /* 2nd */
    LN_CHECK(ntx == 4 && tx[3].seq == 6 && tx[3].nonce != tx[2].nonce);
    LN_CHECK_EQ(s.timeouts_in_row, 2);
    ln_pull_poll(&s, 300); /* 3rd: sync */
    LN_CHECK(ntx == 5 && tx[4].sync);
    LN_CHECK_EQ(s.timeouts_in_row, 3);
    LN_CHECK(!pending(&s, 6));
    /* the late reply to /seq=6 (no longer pending) is dropped and counted */
    LN_CHECK_EQ(reply(&s, 310, 0, 6, 6, 0), 1);
    LN_CHECK_EQ(nrx, 1);
    LN_CHECK_EQ(s.stats.late, 1);
    SYNC(&s, 320, 9);
    LN_CHECK(nrx == 2 && rx[1] == 9 && tx[ntx - 1].seq == 10);
    LN_CHECK_EQ(s.timeouts_in_row, 0);
    /* a reply during a pending retransmission resets the count */
    ln_pull_poll(&s, 420);
    LN_CHECK_EQ(s.timeouts_in_row, 1);
    DATA(&s, 430, 10, 10);
    LN_CHECK_EQ(s.timeouts_in_row, 0);
}

/* ---- pipelining: k slots, never a pending name twice ------------------------------------- */
static void test_window_slots(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.window = 3;
    o.boot_after = 100;
    o.t_max_ms = 100;
    start(&s, &o, 0);
    SYNC(&s, 10, 20);
    LN_CHECK(ntx == 4 && tx[1].seq == 21 && tx[2].seq == 22 && tx[3].seq == 23);
    check_slots(&s);
    /* 22 first: delivered, 21 stays pending (late when it comes), the window refills with 24 */
    DATA(&s, 20, 22, 22);
    LN_CHECK(rx[nrx - 1] == 22 && tx[ntx - 1].seq == 24);
    LN_CHECK(pending(&s, 21) && pending(&s, 23) && pending(&s, 24));
    DATA(&s, 21, 21, 22);
    LN_CHECK_EQ(s.stats.late, 1);
    LN_CHECK(rx[nrx - 1] == 22);
    LN_CHECK(tx[ntx - 1].seq == 25);
    check_slots(&s);
    /* a random script: whatever happens, no two slots hold the same seq and every Interest
     * sent while another for the same seq is pending is a retransmission of that slot */
    uint32_t rng = 99, now = 30;
    for (int step = 0; step < 3000; step++) {
        rng ^= rng << 13, rng ^= rng >> 17, rng ^= rng << 5;
        now += rng % 40;
        int i = (int)(rng >> 8) % o.window;
        if (s.slots[i].seq && rng % 3)
            DATA(&s, now, s.slots[i].seq, s.slots[i].seq + (rng >> 20) % 3);
        else
            ln_pull_poll(&s, now);
        if (s.syncing && (rng >> 12) % 2)
            SYNC(&s, now, s.delivered_seq + 1 + (rng >> 16) % 5);
        check_slots(&s);
        for (int a = 1; a < nrx; a++)
            LN_CHECK(rx[a] > rx[a - 1]); /* strictly increasing delivery */
        if (nrx > 400)
            nrx = 0;
        if (ntx > 400)
            ntx = 0;
    }
}

/* ---- SKIP_OLD: abandon a pending seq once a newer one is delivered ------------------------- */
static void skip_old_case(uint16_t flags, int want_retransmit)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.window = 2;
    o.boot_after = 5;
    o.t_max_ms = 100;
    o.flags = flags;
    start(&s, &o, 0);
    SYNC(&s, 0, 5); /* 6 and 7 pending since 0 */
    int before = ntx;
    DATA(&s, 20, 7, 7); /* 20*4 < 100: t = 50 */
    LN_CHECK_EQ(s.t_ms, 50);
    if (want_retransmit) { /* 6 stays pending: 8 sent at 20; at 50 6 times out: t = 100 */
        LN_CHECK(ntx == before + 1 && tx[before].seq == 8);
        before = ntx;
        ln_pull_poll(&s, 50);
        LN_CHECK_EQ(s.t_ms, 100);
        LN_CHECK(ntx == before + 1 && tx[before].seq == 6);
        LN_CHECK(pending(&s, 6) && pending(&s, 8));
        LN_CHECK_EQ(s.timeouts_in_row, 1);
    } else { /* 6 is abandoned at once (its reply could only be late): 8 and 9 at 20, and
                nothing times out at 50, so neither t nor the timeouts in a row change */
        LN_CHECK(ntx == before + 2 && tx[before].seq == 8 && tx[before + 1].seq == 9);
        LN_CHECK(!pending(&s, 6) && pending(&s, 8) && pending(&s, 9));
        before = ntx;
        LN_CHECK_EQ(ln_pull_poll(&s, 50), 20);
        LN_CHECK(ntx == before && s.t_ms == 50 && s.timeouts_in_row == 0);
        LN_CHECK_EQ(s.stats.timeouts, 0);
        /* the late reply to 6 is dropped */
        LN_CHECK_EQ(reply(&s, 55, 0, 6, 9, 0), 1);
        LN_CHECK(s.stats.late == 1 && rx[nrx - 1] == 7);
    }
}

static void test_skip_old(void)
{
    skip_old_case(0, 1);
    skip_old_case(LN_PULL_SKIP_OLD, 0);
}

/* ---- NACKs and the latest-seq header ---------------------------------------------------- */
static void test_nack_jump(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.t_max_ms = 200;
    start(&s, &o, 0);
    SYNC(&s, 0, 5);
    /* naive: a NACK is counted and nothing else happens; the timer runs out as usual */
    int before = ntx;
    NACK(&s, 10, 6, 90);
    LN_CHECK_EQ(ntx, before);
    LN_CHECK_EQ(s.stats.nacks, 1);
    LN_CHECK(nev > 0 && evs[nev - 1].ev == LN_PULL_EV_NACK && evs[nev - 1].seq == 6);
    LN_CHECK(pending(&s, 6));

    o.flags = LN_PULL_NACK_JUMP;
    start(&s, &o, 0);
    SYNC(&s, 0, 5);
    NACK(&s, 10, 6, 90); /* too old: jump to the producer's newest */
    LN_CHECK(tx[ntx - 1].seq == 90 && pending(&s, 90) && !pending(&s, 6));
    DATA(&s, 20, 90, 90);
    LN_CHECK(rx[nrx - 1] == 90 && tx[ntx - 1].seq == 91);
    NACK(&s, 30, 91, 90); /* beyond what the producer parks: the timer retries */
    LN_CHECK(tx[ntx - 1].seq == 91 && pending(&s, 91) && !s.syncing);
    NACK(&s, 40, 91, 0); /* no sample at all (the producer started over): re-bootstrap */
    LN_CHECK(s.syncing && tx[ntx - 1].sync);
    NACK(&s, 45, 0, 0); /* the sync refused as well: wait for its timer */
    LN_CHECK_EQ(s.stats.nacks, 4);
    LN_CHECK(s.syncing);
    SYNC(&s, 50, 3); /* below what was delivered: the producer restarted; start over from 3 */
    LN_CHECK(rx[nrx - 1] == 3 && s.delivered_seq == 3 && tx[ntx - 1].seq == 4);

    /* the latest-seq header of a sample: behind by more than one, jump */
    ln_pull_options_naive(&o);
    o.flags = LN_PULL_NACK_JUMP;
    start(&s, &o, 0);
    SYNC(&s, 0, 5);
    DATA(&s, 10, 6, 20);
    LN_CHECK(tx[ntx - 1].seq == 20);
    o.flags = 0;
    start(&s, &o, 0);
    SYNC(&s, 0, 5);
    DATA(&s, 10, 6, 20);
    LN_CHECK(tx[ntx - 1].seq == 7);

    /* an NDNLPv2 Nack of our pending Interest: a fast failure with NACK_JUMP */
    o.flags = LN_PULL_NACK_JUMP;
    o.boot_after = 2;
    start(&s, &o, 0);
    SYNC(&s, 0, 5);
    {
        uint8_t name[96], in_buf[160], lp[200];
        ln_ndn_interest in;
        int n = ln_ndn_name_from_uri(name, sizeof name, TOPIC "/seq=6");
        memset(&in, 0, sizeof in);
        in.name.data = name;
        in.name.size = (size_t)n;
        in.nonce = tx[ntx - 1].nonce;
        in.lifetime_ms = 2000;
        n = ln_ndn_encode_interest(in_buf, sizeof in_buf, &in);
        lp[0] = 0x64;
        lp[1] = (uint8_t)(4 + 2 + n);
        lp[2] = 0xfd, lp[3] = 0x03, lp[4] = 0x20, lp[5] = 0x00;
        lp[6] = 0x50;
        lp[7] = (uint8_t)n;
        memcpy(lp + 8, in_buf, (size_t)n);
        before = ntx;
        LN_CHECK_EQ(ln_pull_receive(&s, lp, 8 + (size_t)n, 10), 1);
        LN_CHECK_EQ(s.stats.timeouts, 1);
        LN_CHECK(ntx == before + 1 && tx[before].seq == 6 && tx[before].nonce != in.nonce);
        /* the Nack of an Interest no longer pending (old nonce): late */
        LN_CHECK_EQ(ln_pull_receive(&s, lp, 8 + (size_t)n, 11), 1);
        LN_CHECK_EQ(s.stats.late, 1);
    }
}

/* ---- the t/4 rule on sync replies, Karn's rule ------------------------------------------- */
static void test_sync_quarter_and_karn(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.t_max_ms = 400;
    start(&s, &o, 0);
    SYNC(&s, 99, 5); /* 99*4 < 400 but naive leaves t */
    LN_CHECK_EQ(s.t_ms, 400);
    o.flags = LN_PULL_SYNC_QUARTER;
    start(&s, &o, 0);
    SYNC(&s, 99, 5);
    LN_CHECK_EQ(s.t_ms, 200);
    start(&s, &o, 0);
    SYNC(&s, 100, 5); /* Δ = t/4 exactly: no */
    LN_CHECK_EQ(s.t_ms, 400);

    /* Karn: the reply to a retransmission does not halve t */
    for (int karn = 0; karn < 2; karn++) {
        o.flags = karn ? LN_PULL_KARN : 0;
        o.boot_after = 3;
        start(&s, &o, 0);
        SYNC(&s, 0, 5);        /* /seq=6 at 0 */
        ln_pull_poll(&s, 400); /* timeout: t 400 (cap), retransmitted at 400 */
        LN_CHECK_EQ(s.slot_state[0] & LN_PULL_SLOT_RETRIES, 1);
        DATA(&s, 401, 6, 6); /* 1*4 < 400 */
        LN_CHECK_EQ(s.t_ms, karn ? 400 : 200);
        DATA(&s, 402, 7, 7); /* a first transmission: halves either way */
        LN_CHECK_EQ(s.t_ms, karn ? 200 : 100);
    }
}

/* ---- SLOT_OFFSET: slot j times out after t + (j-1)·P̂ ----------------------------------------- */
static void test_slot_offset(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_hardened(&o, 100);
    LN_CHECK(o.t_max_ms == 100 && o.t_min_ms == 10 && o.window == 3 && o.boot_after == 3);
    o.flags = LN_PULL_SLOT_OFFSET;
    start(&s, &o, 0);
    SYNC(&s, 0, 10); /* P̂ starts at the header's mean period, 20 ms; 11 12 13 at 0 */
    LN_CHECK_EQ(s.period_ewma_us, 20000);
    /* at 0 the newest delivered is 10: 11 is j=1 (t), 12 j=2 (t + P̂), 13 j=3 (t + 2·P̂) */
    LN_CHECK(tx[1].lifetime == 100 && tx[2].lifetime == 120 && tx[3].lifetime == 140);
    /* an arrival 40 ms after the last one (Δ ≥ t/4: t stays 100): P̂ = 20 + (40-20)/8 = 22.5 */
    DATA(&s, 40, 11, 11);
    LN_CHECK_EQ(s.period_ewma_us, 22500);
    /* 14 is j=3: lifetime 100 + 2·23 (P̂ in ms, rounded) */
    LN_CHECK(tx[ntx - 1].seq == 14 && tx[ntx - 1].lifetime == 146);
    DATA(&s, 80, 12, 12); /* P̂ = 22.5 + (40-22.5)/8 = 24.687 */
    LN_CHECK_EQ(s.period_ewma_us, 24687);
    /* the timers run from the later of the send and the newest arrival (80):
       13 (j=1, sent at 0) is due at 80+100 = 180; 14 (j=2, sent at 40) at 80+100+25 = 205;
       15 (j=3, sent at 80) at 80+100+2·25 = 230 */
    LN_CHECK_EQ(ln_pull_poll(&s, 81), 99);
    int before = ntx;
    ln_pull_poll(&s, 179);
    LN_CHECK(ntx == before);
    ln_pull_poll(&s, 180);
    LN_CHECK(ntx == before + 1 && tx[before].seq == 13); /* retransmitted */
    LN_CHECK_EQ(s.t_ms, 100);
    LN_CHECK_EQ(ln_pull_poll(&s, 204), 1); /* 14 next, at 205; 13 again at 280 */
    LN_CHECK(ntx == before + 1);
    ln_pull_poll(&s, 205);
    LN_CHECK(ntx == before + 2 && tx[before + 1].seq == 14);
    /* without the option every slot times out after t */
    o.flags = 0;
    start(&s, &o, 0);
    SYNC(&s, 0, 10);
    LN_CHECK(tx[1].lifetime == 100 && tx[2].lifetime == 100 && tx[3].lifetime == 100);
    LN_CHECK_EQ(ln_pull_poll(&s, 1), 99);
}

/* ---- SYNC_SLOTS: while syncing, the slots ask for latest+1.. too ------------------------------ */
static void test_sync_slots(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.window = 3;
    o.t_max_ms = 100;
    o.flags = LN_PULL_SYNC_SLOTS;
    start(&s, &o, 0);
    LN_CHECK(ntx == 1 && tx[0].sync); /* no latest known yet: the first sync goes alone */
    SYNC(&s, 10, 5);
    LN_CHECK(ntx == 4 && tx[1].seq == 6 && tx[2].seq == 7 && tx[3].seq == 8);
    DATA(&s, 20, 6, 9); /* 10*4 < 100: t = 50; 9 at 20; the producer's latest is 9 */
    LN_CHECK(s.t_ms == 50 && tx[ntx - 1].seq == 9);
    int before = ntx;
    ln_pull_poll(&s, 60); /* 7 (sent at 10) times out: t = 100, boot_after 1: sync */
    LN_CHECK(s.syncing && s.t_ms == 100 && s.timeouts_in_row == 1);
    LN_CHECK(ntx == before + 4 && tx[before].sync && tx[before + 1].seq == 10 &&
             tx[before + 2].seq == 11 && tx[before + 3].seq == 12);
    LN_CHECK(tx[before].lifetime == 100 && tx[before + 3].lifetime == 100);
    LN_CHECK(!pending(&s, 8) && !pending(&s, 9));
    LN_CHECK_EQ(ln_pull_poll(&s, 61), 99); /* only the sync's timer runs */
    uint32_t n10 = tx[before + 1].nonce;
    before = ntx;
    ln_pull_poll(&s, 160); /* the sync timed out: all four again, new nonces */
    LN_CHECK(ntx == before + 4 && tx[before].sync && tx[before + 1].seq == 10 &&
             tx[before + 1].nonce != n10 && tx[before + 3].seq == 12);
    LN_CHECK(s.syncing && s.t_ms == 100 && s.timeouts_in_row == 2);
    DATA(&s, 170, 11, 11); /* a sample ends the re-bootstrap: 13 takes its slot */
    LN_CHECK(!s.syncing && rx[nrx - 1] == 11 && s.timeouts_in_row == 0);
    LN_CHECK(pending(&s, 10) && pending(&s, 12) && pending(&s, 13) && tx[ntx - 1].seq == 13);
    LN_CHECK_EQ(reply(&s, 175, 1, 11, 11, 0), 1); /* the sync's reply comes late */
    LN_CHECK_EQ(s.stats.late, 1);
    /* a NACK saying that the producer started over while syncing does not sync again */
    ln_pull_poll(&s, 270);
    LN_CHECK(s.syncing);
    before = ntx;
    NACK(&s, 275, tx[ntx - 1].seq, 2);
    LN_CHECK(ntx == before && s.syncing);
    /* without the flag the sync goes alone */
    o.flags = 0;
    start(&s, &o, 0);
    SYNC(&s, 10, 5);
    DATA(&s, 20, 6, 9);
    before = ntx;
    ln_pull_poll(&s, 60);
    LN_CHECK(ntx == before + 1 && tx[before].sync && s.syncing);
}

/* ---- REFRESH: a pending Interest goes out once more when a sample arrives ------------------- */
static void test_refresh(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.window = 3;
    o.boot_after = 3;
    o.t_max_ms = 100;
    o.flags = LN_PULL_REFRESH;
    start(&s, &o, 0);
    SYNC(&s, 0, 10); /* P̂ = 20 ms (header); 11 12 13 at 0 */
    uint32_t n12 = tx[2].nonce, n13 = tx[3].nonce;
    DATA(&s, 20, 11, 11); /* 12, 13 pending for 20 >= P̂/2: sent once more, then 14 */
    LN_CHECK_EQ(s.stats.refreshes, 2);
    LN_CHECK(tx[ntx - 3].seq == 12 && tx[ntx - 3].nonce != n12 && tx[ntx - 2].seq == 13 &&
             tx[ntx - 2].nonce != n13 && tx[ntx - 1].seq == 14);
    LN_CHECK(s.slots[1].sent_ms == 20 && s.slot_state[1] == LN_PULL_SLOT_REFRESHED);
    LN_CHECK_EQ(s.t_ms, 50); /* 20*4 < 100 */
    /* a refreshed reply is not a retransmission: its Δ counts from the refresh */
    DATA(&s, 25, 12, 12); /* 13 was refreshed already, 14 only 5 ms ago: none; 15 at 25 */
    LN_CHECK(s.stats.refreshes == 2 && tx[ntx - 1].seq == 15);
    LN_CHECK_EQ(s.t_ms, 25);              /* Δ = 25 - 20: 5*4 < 50 */
    LN_CHECK_EQ(s.period_ewma_us, 18125); /* 20 - (20-5)/8 */
    DATA(&s, 45, 13, 13); /* 14 (20 at 25 ms) and 15 (at 20 ms) >= P̂/2: both; then 16 */
    LN_CHECK_EQ(s.stats.refreshes, 4);
    LN_CHECK(tx[ntx - 3].seq == 14 && tx[ntx - 2].seq == 15 && tx[ntx - 1].seq == 16);
    LN_CHECK_EQ(s.t_ms, 25); /* Δ = 45 - 20 = 25: not quick */
    DATA(&s, 50, 14, 14);    /* Δ = 5: t = 12; 16 (sent at 45) too recent; 17 at 50 */
    LN_CHECK(s.t_ms == 12 && s.stats.refreshes == 4 && tx[ntx - 1].seq == 17);
    /* a seq published before a new Interest could get there ((seq - newest)·P̂ <= SRTT) is
       not refreshed: with SRTT 30 ms and P̂ = 17.1 ms, 17 (2 ahead of 15) is, 16 is not */
    s.srtt_us = 30000;
    int before = ntx;
    DATA(&s, 70, 15, 15);
    LN_CHECK_EQ(s.period_ewma_us, 17103);
    LN_CHECK(ntx == before + 2 && tx[before].seq == 17 && tx[before + 1].seq == 18);
    LN_CHECK_EQ(s.stats.refreshes, 5);
    /* without the flag nothing is sent again */
    o.flags = 0;
    start(&s, &o, 0);
    SYNC(&s, 0, 10);
    DATA(&s, 20, 11, 11);
    LN_CHECK(ntx == 5 && tx[4].seq == 14 && s.stats.refreshes == 0);
    /* only while a loss was seen in the last LN_PULL_REFRESH_SPAN samples (or since start) */
    o.flags = LN_PULL_REFRESH;
    start(&s, &o, 0);
    SYNC(&s, 0, 10); /* 1 delivered */
    uint32_t now = 0;
    uint64_t q = 11;
    for (; q < 9 + LN_PULL_REFRESH_SPAN; q++) { /* 2 at 11, then one per sample */
        now += 20;
        DATA(&s, now, q, q);
        LN_CHECK_EQ(s.stats.refreshes, (uint32_t)(q - 9));
        ntx = ntx > 400 ? 0 : ntx, nrx = nrx > 400 ? 0 : nrx;
    }
    /* the 64th delivered without a loss: off */
    LN_CHECK_EQ(s.since_loss, LN_PULL_REFRESH_SPAN - 1);
    uint32_t refreshed = s.stats.refreshes;
    before = ntx;
    DATA(&s, now += 20, q, q);
    LN_CHECK(s.stats.refreshes == refreshed && ntx == before + 1);
    DATA(&s, now += 20, q + 2, q + 2); /* q + 1 skipped: a loss, on again */
    LN_CHECK(s.since_loss == 0 && s.stats.refreshes > refreshed);
    ln_pull_poll(&s, now + 1000); /* a timeout is a loss too */
    LN_CHECK(s.stats.timeouts > 0 && s.since_loss == 0);
}

/* ---- AUTO_WINDOW: ceil(SRTT/P̂)+k slots, SRTT from replies to published seqs -------------- */
static void test_auto_window(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.window = 2;
    o.boot_after = 3;
    o.t_max_ms = 200;
    o.flags = LN_PULL_AUTO_WINDOW | LN_PULL_NACK_JUMP;
    start(&s, &o, 0);
    SYNC(&s, 50, 100); /* RTT 50 ms, P̂ 20 ms: ceil(2.5)+2 = 5 slots, 101..105 at 50 */
    LN_CHECK(s.srtt_us == 50000 && s.window == 5);
    LN_CHECK(ntx == 6 && tx[1].seq == 101 && tx[5].seq == 105);
    /* 101..105 were not published when sent: a reply is no RTT, but its Δ is at least one:
       Δ = 10 ms < SRTT lowers it to 50 - (50-10)/8 = 45 ms.
       P̂ = 20 - (20-10)/8 = 18.75 ms: ceil(45/18.75)+2 = 5 */
    DATA(&s, 60, 101, 101);
    LN_CHECK(s.srtt_us == 45000 && s.period_ewma_us == 18750 && s.window == 5);
    LN_CHECK(tx[ntx - 1].seq == 106);
    /* a NACK jump asks for a published seq: its reply is an RTT sample */
    NACK(&s, 61, 102, 110); /* 102 -> 110 (published), 111 next */
    LN_CHECK(pending(&s, 110) && s.slot_state[1] == LN_PULL_SLOT_PUBLISHED);
    DATA(&s, 63, 110, 110); /* RTT 2 ms: SRTT = 45 - 43/8 = 39.625 ms */
    LN_CHECK_EQ(s.srtt_us, 39625);
    /* P̂ = 18.75 - (18.75 - 0.333)/8 = 16.45 ms: ceil(39.6/16.45)+2 = 5 */
    LN_CHECK(s.period_ewma_us == 16448 && s.window == 5);
    /* fast replies (SRTT <= P̂) shrink it to 1 + opt.window (slots beyond it run out) */
    for (uint32_t i = 0, now = 70; i < 40; i++, now += 20) {
        uint64_t l = 200 + 3 * i;
        for (int j = 0; j < LN_PULL_MAX_WINDOW; j++)
            if (s.slots[j].seq && s.slots[j].seq < l) {
                NACK(&s, now, s.slots[j].seq, l); /* jump to l (published) */
                break;
            }
        if (pending(&s, l))
            DATA(&s, now + 1, l, l); /* RTT 1 ms */
        else
            ln_pull_poll(&s, now + 1);
        check_slots(&s);
    }
    LN_CHECK(s.srtt_us < 11000 && s.srtt_us <= s.period_ewma_us && s.window == 3);
    int used = 0;
    for (int j = 0; j < LN_PULL_MAX_WINDOW; j++)
        used += s.slots[j].seq != 0;
    LN_CHECK(used <= 3);
    /* without the flag the window stays */
    o.flags = LN_PULL_NACK_JUMP;
    start(&s, &o, 0);
    SYNC(&s, 50, 100);
    LN_CHECK(s.window == 2 && ntx == 3);
    /* a parked reply slower than SRTT is no sample (it may have waited for the publish) */
    o.flags = LN_PULL_AUTO_WINDOW;
    start(&s, &o, 0);
    SYNC(&s, 10, 100); /* SRTT 10 ms */
    DATA(&s, 40, 101, 101);
    LN_CHECK_EQ(s.srtt_us, 10000);
}

/* ---- ln_pull_start_name: a pre-encoded name ------------------------------------------------- */
static void test_start_name(void)
{
    ln_pull_sub s, u;
    ln_pull_options o;
    uint8_t name[128];
    ln_pull_options_hardened(&o, 100);
    reset();
    int n = ln_ndn_name_from_uri(name, sizeof name, TOPIC);
    LN_CHECK_EQ(ln_pull_start_name(&s, name, (size_t)n, &o, on_send, on_data, on_event, NULL, 0, 7),
                LN_NDN_OK);
    LN_CHECK(ntx == 1 && tx[0].sync && tx[0].lifetime == 100);
    LN_CHECK_EQ(ln_pull_start(&u, TOPIC, &o, on_send, on_data, on_event, NULL, 0, 7), LN_NDN_OK);
    LN_CHECK(ntx == 2 && tx[1].nonce == tx[0].nonce);
    LN_CHECK(memcmp(&s, &u, sizeof s) == 0); /* the same subscription either way */
    SYNC(&s, 5, 9);
    LN_CHECK(rx[nrx - 1] == 9 && s.window == 4 && tx[ntx - 1].seq == 13); /* ceil(5/20) + 3 */
    LN_CHECK_EQ(ln_pull_start_name(&s, name, 0, &o, on_send, NULL, NULL, NULL, 0, 7), LN_NDN_ENAME);
    name[1] = 200; /* a component longer than the name */
    LN_CHECK_EQ(ln_pull_start_name(&s, name, (size_t)n, &o, on_send, NULL, NULL, NULL, 0, 7),
                LN_NDN_ENAME);
    memset(name, 0, sizeof name);
    LN_CHECK_EQ(
        ln_pull_start_name(&s, name, LN_PULL_MAX_NAME + 1, &o, on_send, NULL, NULL, NULL, 0, 7),
        LN_NDN_ESPACE);
    LN_CHECK_EQ(ln_pull_start_name(&s, NULL, 4, &o, on_send, NULL, NULL, NULL, 0, 7),
                LN_NDN_EINVAL);
}

/* ---- the polling baseline (not in a device build, which refuses it) -------------------------- */
static void test_polling(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.poll_ms = 50;
#ifdef LN_NDN_CONSUMER
    reset();
    LN_CHECK_EQ(ln_pull_start(&s, TOPIC, &o, on_send, on_data, on_event, NULL, 1000, 7),
                LN_NDN_EINVAL);
    LN_CHECK_EQ(ntx, 0);
    return;
#endif
    start(&s, &o, 1000);
    LN_CHECK(ntx == 1 && tx[0].sync && tx[0].lifetime == 50);
    LN_CHECK_EQ(ln_pull_poll(&s, 1049), 1);
    LN_CHECK_EQ(ntx, 1);
    LN_CHECK_EQ(ln_pull_poll(&s, 1050), 50); /* unanswered poll: a timeout, next poll */
    LN_CHECK(ntx == 2 && tx[1].sync);
    LN_CHECK_EQ(s.stats.timeouts, 1);
    SYNC(&s, 1060, 3);
    SYNC(&s, 1061, 3); /* the same sample again: not delivered twice */
    LN_CHECK(nrx == 1 && rx[0] == 3);
    LN_CHECK_EQ(ntx, 2);                     /* replies send nothing: only the clock does */
    LN_CHECK_EQ(ln_pull_poll(&s, 1130), 20); /* late poll at 1130: the schedule stays 1100+50k */
    LN_CHECK_EQ(ntx, 3);
    LN_CHECK_EQ(s.stats.timeouts, 1);
    SYNC(&s, 1131, 7);
    SYNC(&s, 1132, 5); /* an older reply arriving late */
    LN_CHECK(nrx == 2 && rx[1] == 7);
    LN_CHECK_EQ(s.stats.late, 1);
    LN_CHECK_EQ(ln_pull_poll(&s, 5000), 50); /* far behind: restart the schedule at now */
    LN_CHECK_EQ(s.t_ms, 2000);               /* no DIT in polling mode */
    LN_CHECK(!pending(&s, 8));
}

/* ---- other packets, wrap-around ---------------------------------------------------------------- */
static void test_other_packets(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    uint8_t b[200], name[96];
    ln_pull_options_naive(&o);
    start(&s, &o, 0);
    LN_CHECK(ln_pull_receive(&s, (const uint8_t*)"\x06\x01", 2, 0) < 0);
    LN_CHECK_EQ(s.stats.bad, 1);
    /* Data of another topic: not ours, not counted */
    ln_ndn_data d;
    ln_ndn_signer sig = {LN_NDN_SIG_DIGEST_SHA256, NULL, 0, {NULL, 0}};
    memset(&d, 0, sizeof d);
    d.name.data = name;
    d.name.size = (size_t)ln_ndn_name_from_uri(name, sizeof name, "/ln/robot/other/seq=3");
    int n = ln_ndn_encode_data(b, sizeof b, &d, &sig);
    LN_CHECK_EQ(ln_pull_receive(&s, b, (size_t)n, 0), 0);
    d.name.size = (size_t)ln_ndn_name_from_uri(name, sizeof name, TOPIC "/sub/seq=3");
    n = ln_ndn_encode_data(b, sizeof b, &d, &sig);
    LN_CHECK_EQ(ln_pull_receive(&s, b, (size_t)n, 0), 0);
    /* an Interest is never a reply */
    ln_ndn_interest in;
    memset(&in, 0, sizeof in);
    in.name = d.name;
    n = ln_ndn_encode_interest(b, sizeof b, &in);
    LN_CHECK_EQ(ln_pull_receive(&s, b, (size_t)n, 0), LN_NDN_EUNSUPPORTED);
    /* our name with a content that does not decode */
    d.name.size = (size_t)ln_ndn_name_from_uri(name, sizeof name, TOPIC "/sync/seq=3");
    d.content.data = (const uint8_t*)"\x81\x00";
    d.content.size = 2;
    n = ln_ndn_encode_data(b, sizeof b, &d, &sig);
    LN_CHECK_EQ(ln_pull_receive(&s, b, (size_t)n, 0), LN_NDN_ECRITICAL);
    LN_CHECK_EQ(s.stats.bad, 3);
    LN_CHECK_EQ(nrx, 0);
}

static void test_wrap_around(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    o.boot_after = 2;
    o.t_max_ms = 100;
    uint32_t t0 = 0xffffffffu - 30;
    start(&s, &o, t0);
    SYNC(&s, t0 + 10, 1); /* /seq=2 at t0+10 */
    LN_CHECK_EQ(ln_pull_poll(&s, t0 + 20), 90);
    LN_CHECK_EQ(ln_pull_poll(&s, t0 + 109), 1); /* past the wrap */
    int before = ntx;
    ln_pull_poll(&s, t0 + 110);
    LN_CHECK(ntx == before + 1 && tx[before].seq == 2);
    DATA(&s, t0 + 111, 2, 2); /* Δ = 1 across the wrap: halves */
    LN_CHECK_EQ(s.t_ms, 50);
}

/* ---- 64-bit seqs (a device build keeps 32-bit offsets from a base: docs/pull.md, "Sizes") --- */
static void test_big_seqs(void)
{
    ln_pull_sub s;
    ln_pull_options o;
    const uint64_t big = ((uint64_t)1 << 40) + 5, edge = 0xffff0000u;
    ln_pull_options_naive(&o);
    o.t_max_ms = 100;
    start(&s, &o, 0);
    SYNC(&s, 10, big); /* far above 2^32 from the start */
    LN_CHECK(nrx == 1 && rx[0] == big && tx[ntx - 1].seq == big + 1);
    DATA(&s, 20, big + 1, big + 1);
    LN_CHECK(nrx == 2 && rx[1] == big + 1 && tx[ntx - 1].seq == big + 2);
    LN_CHECK_EQ(reply(&s, 21, 0, big + 2 + ((uint64_t)1 << 33), 0, 0), 1); /* no such Interest */
    LN_CHECK(s.stats.late == 1 && nrx == 2);
    ln_pull_poll(&s, 200); /* /seq=big+2 times out: reported with its 64-bit seq, then sync */
    LN_CHECK(nev >= 2 && evs[nev - 2].ev == LN_PULL_EV_TIMEOUT && evs[nev - 2].seq == big + 2);
    LN_CHECK(evs[nev - 1].ev == LN_PULL_EV_SYNC && evs[nev - 1].seq == big + 1);
    SYNC(&s, 210, 3); /* the producer started over */
    LN_CHECK(nrx == 3 && rx[2] == 3 && tx[ntx - 1].seq == 4);
    DATA(&s, 220, 4, 4);
    LN_CHECK(nrx == 4 && rx[3] == 4 && tx[ntx - 1].seq == 5);
    /* 2^32 - 2^16 seqs past the base (0 here) */
    start(&s, &o, 0);
    SYNC(&s, 10, edge);
    LN_CHECK(nrx == 1 && rx[0] == edge && tx[ntx - 1].seq == edge + 1);
#ifdef LN_NDN_CONSUMER
    /* beyond the range a device build follows: late, then one re-bootstrap re-bases it */
    DATA(&s, 20, edge + 1, edge + 1);
    LN_CHECK(nrx == 1 && s.stats.late == 1);
    ln_pull_poll(&s, 200);
    LN_CHECK(tx[ntx - 1].sync);
    SYNC(&s, 210, edge + 1);
#else
    DATA(&s, 20, edge + 1, edge + 1);
#endif
    LN_CHECK(nrx == 2 && rx[1] == edge + 1 && tx[ntx - 1].seq == edge + 2);
    DATA(&s, 230, edge + 2, edge + 2);
    LN_CHECK(nrx == 3 && rx[2] == edge + 2 && tx[ntx - 1].seq == edge + 3);
}

#if !defined(LN_NDN_CONSUMER) || defined(LN_PULL_HMAC)
/* ---- HMAC-SHA256 verification (a device build has it with -DLN_PULL_HMAC) ------------------ */
static void test_verify_key(void)
{
    static const uint8_t key[20] = "0123456789abcdefghij", other_key[3] = "key";
    uint8_t long_key[100];
    ln_ndn_signer hmac = {LN_NDN_SIG_HMAC_SHA256, key, sizeof key, {NULL, 0}};
    ln_ndn_signer other = {LN_NDN_SIG_HMAC_SHA256, other_key, sizeof other_key, {NULL, 0}};
    ln_ndn_signer digest = {LN_NDN_SIG_DIGEST_SHA256, NULL, 0, {NULL, 0}};
    ln_pull_sub s;
    ln_pull_options o;
    ln_pull_options_naive(&o);
    start(&s, &o, 0);
    LN_CHECK_EQ(ln_pull_set_verify_key(NULL, key, sizeof key), LN_NDN_EINVAL);
    LN_CHECK_EQ(ln_pull_set_verify_key(&s, NULL, 3), LN_NDN_EINVAL);
    LN_CHECK_EQ(ln_pull_set_verify_key(&s, key, sizeof key), LN_NDN_OK);
    const ln_ndn_signer* refused[] = {&digest, &other, &hmac};
    for (int i = 0; i < 3; i++) { /* unsigned, another key, tampered: none is taken */
        reply_signer = refused[i];
        reply_tampered = i == 2;
        LN_CHECK_EQ(reply(&s, 5, 1, 7, 7, 0), LN_NDN_ESIGNATURE);
    }
    reply_tampered = 0;
    LN_CHECK(nrx == 0 && s.stats.rejected == 3 && s.stats.bad == 0 && s.syncing);
    reply_signer = &hmac;
    SYNC(&s, 6, 7);
    LN_CHECK(nrx == 1 && rx[0] == 7 && s.stats.rejected == 3);
    reply_signer = &other; /* a NACK must verify as well */
    LN_CHECK_EQ(reply(&s, 7, 0, 8, 9, 1), LN_NDN_ESIGNATURE);
    LN_CHECK(s.stats.nacks == 0 && s.stats.rejected == 4);
    /* a key longer than a block is hashed first (RFC 2104) */
    for (int i = 0; i < 100; i++)
        long_key[i] = (uint8_t)(i * 7);
    hmac.key = long_key;
    hmac.key_size = sizeof long_key;
    LN_CHECK_EQ(ln_pull_set_verify_key(&s, long_key, sizeof long_key), LN_NDN_OK);
    reply_signer = &hmac;
    DATA(&s, 8, 8, 8);
    LN_CHECK(nrx == 2 && rx[1] == 8);
    /* verification off: both kinds are taken again */
    LN_CHECK_EQ(ln_pull_set_verify_key(&s, NULL, 0), LN_NDN_OK);
    reply_signer = NULL;
    DATA(&s, 9, 9, 9);
    LN_CHECK(nrx == 3 && s.stats.rejected == 4);
    /* ln_pull_start clears it */
    LN_CHECK_EQ(ln_pull_set_verify_key(&s, key, sizeof key), LN_NDN_OK);
    start(&s, &o, 20);
    SYNC(&s, 25, 30);
    LN_CHECK(nrx == 1 && s.stats.rejected == 0);
}
#endif

int main(void)
{
    LN_TEST_RUN(test_naive_sequence);
    LN_TEST_RUN(test_floor_and_cap);
    LN_TEST_RUN(test_reboot_after);
    LN_TEST_RUN(test_window_slots);
    LN_TEST_RUN(test_skip_old);
    LN_TEST_RUN(test_nack_jump);
    LN_TEST_RUN(test_sync_quarter_and_karn);
    LN_TEST_RUN(test_slot_offset);
    LN_TEST_RUN(test_sync_slots);
    LN_TEST_RUN(test_refresh);
    LN_TEST_RUN(test_auto_window);
    LN_TEST_RUN(test_start_name);
    LN_TEST_RUN(test_polling);
    LN_TEST_RUN(test_other_packets);
    LN_TEST_RUN(test_wrap_around);
    LN_TEST_RUN(test_big_seqs);
#if !defined(LN_NDN_CONSUMER) || defined(LN_PULL_HMAC)
    LN_TEST_RUN(test_verify_key);
#endif
    printf("sizeof(ln_pull_sub) = %zu\n", sizeof(ln_pull_sub));
    LN_TEST_EXIT();
}
