/* fuzz_ndn.c — fuzz target: libln_pull's NDN decoder (ln_ndn_decode,
 * ln_ndn_decode_pull_content) and the pull consumer (ln_pull_receive, ln_pull_poll).  The
 * input is an options byte, then records [u16 big-endian length][u8 ms to advance][packet];
 * each packet is decoded (what decodes must encode and decode back to the same fields, and
 * its name must survive the URI round trip) and fed to a fresh subscription to
 * /ln/robot/arm.state, whose pending names must stay distinct. */
#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "ln/pull.h"

#define TOPIC "/ln/robot/arm.state"

static void sent(void* user, const uint8_t* packet, size_t size)
{
    ln_ndn_packet p;
    int rc = ln_ndn_decode(packet, size, &p);
    assert(rc == LN_NDN_OK && p.type == LN_NDN_T_INTEREST && size <= LN_PULL_TX_BYTES);
    (void)rc;
    (void)user;
}

static void check_slots(const ln_pull_sub* s)
{
    for (int i = 0; i < LN_PULL_MAX_WINDOW; i++) /* an auto window uses more than opt.window */
        for (int j = i + 1; j < LN_PULL_MAX_WINDOW; j++)
            assert(!s->slots[i].seq || s->slots[i].seq != s->slots[j].seq);
    assert(s->t_ms >= s->opt.t_min_ms && s->t_ms <= s->opt.t_max_ms);
}

static int same(ln_ndn_bytes a, ln_ndn_bytes b)
{
    return a.size == b.size && (a.size == 0 || memcmp(a.data, b.data, a.size) == 0);
}

/* The same components (types and values): a name read with non-minimal VAR-NUMBERs comes
 * back from its URI in the shortest encoding, so the bytes may differ. */
static int same_components(ln_ndn_bytes a, ln_ndn_bytes b)
{
    ln_ndn_component ca, cb;
    int ra, rb;
    do {
        ra = ln_ndn_name_next(&a, &ca);
        rb = ln_ndn_name_next(&b, &cb);
        if (ra != rb || (ra == 1 && (ca.type != cb.type || !same(ca.value, cb.value))))
            return 0;
    } while (ra == 1);
    return ra == 0;
}

static void name_round_trip(ln_ndn_bytes name)
{
    size_t cap = name.size * 8 + 16;
    char* uri = malloc(cap);
    uint8_t* back = malloc(name.size + 1);
    if (uri && back && ln_ndn_name_to_uri(uri, cap, name) > 0) {
        int n = ln_ndn_name_from_uri(back, name.size + 1, uri);
        ln_ndn_bytes b = {back, n > 0 ? (size_t)n : 0};
        assert(n >= 0 && same_components(b, name));
    }
    free(uri);
    free(back);
}

static void decode_one(const uint8_t* data, size_t size)
{
    ln_ndn_packet p, q;
    ln_ndn_pull_content c;
    if (ln_ndn_decode(data, size, &p) != LN_NDN_OK)
        return;
    size_t cap = size + 64;
    uint8_t* out = malloc(cap);
    if (!out)
        return;
    if (p.type == LN_NDN_T_INTEREST) {
        name_round_trip(p.interest.name);
        ln_ndn_interest in = p.interest;
        in.app_parameters.size = 0;
        int n = ln_ndn_encode_interest(out, cap, &in);
        assert(n > 0);
        int rc = ln_ndn_decode(out, (size_t)n, &q);
        assert(rc == LN_NDN_OK && same(q.interest.name, p.interest.name) &&
               q.interest.nonce == p.interest.nonce &&
               q.interest.lifetime_ms == p.interest.lifetime_ms &&
               q.interest.can_be_prefix == p.interest.can_be_prefix &&
               q.interest.must_be_fresh == p.interest.must_be_fresh &&
               q.interest.hop_limit == p.interest.hop_limit);
        (void)rc;
    } else {
        ln_ndn_signer digest = {LN_NDN_SIG_DIGEST_SHA256, NULL, 0, {NULL, 0}};
        name_round_trip(p.data.name);
        ln_ndn_verify(&p.data, &digest);
        if (ln_ndn_decode_pull_content(p.data.content, &c) == LN_NDN_OK && c.payload.size)
            assert(c.payload.data >= p.data.content.data &&
                   c.payload.data + c.payload.size <= p.data.content.data + p.data.content.size);
        int n = ln_ndn_encode_data(out, cap, &p.data, &digest);
        assert(n > 0);
        int rc = ln_ndn_decode(out, (size_t)n, &q);
        assert(rc == LN_NDN_OK && same(q.data.name, p.data.name) &&
               same(q.data.content, p.data.content) && q.data.content_type == p.data.content_type &&
               q.data.freshness_ms == p.data.freshness_ms &&
               ln_ndn_verify(&q.data, &digest) == LN_NDN_OK);
        (void)rc;
    }
    free(out);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static ln_pull_sub sub;
    ln_pull_options o;
    uint32_t now = 0xfffff000u; /* wraps during longer inputs */
    decode_one(data, size);     /* the whole input as one packet as well */
    if (size < 1)
        return 0;
    uint8_t mode = data[0];
    if (mode & 1)
        ln_pull_options_hardened(&o, 20 + (mode >> 4) * 10);
    else
        ln_pull_options_naive(&o);
    if (mode & 2)
        o.window = 1 + (mode >> 2) % LN_PULL_MAX_WINDOW;
    if ((mode & 0x0e) == 0x0e)
        o.poll_ms = 1 + (mode >> 4);
    int rc = ln_pull_start(&sub, TOPIC, &o, sent, NULL, NULL, NULL, now, mode);
    assert(rc == LN_NDN_OK);
    (void)rc;
    data++, size--;
    while (size >= 3) {
        size_t n = (size_t)data[0] << 8 | data[1];
        now += data[2];
        data += 3, size -= 3;
        if (n > size)
            n = size;
        uint8_t* packet = malloc(n ? n : 1); /* exactly n bytes: reads beyond are caught */
        if (!packet)
            return 0;
        memcpy(packet, data, n);
        decode_one(packet, n);
        int r = ln_pull_receive(&sub, packet, n, now);
        assert(r == 0 || r == 1 || (r < 0 && r >= LN_NDN_EDEPTH));
        free(packet);
        check_slots(&sub);
        ln_pull_poll(&sub, now);
        check_slots(&sub);
        data += n, size -= n;
    }
    return 0;
}

/* ---- seeds, from our own encoders -------------------------------------------------------- */
static size_t reply(uint8_t* out, size_t cap, const char* uri, uint64_t seq, uint64_t latest,
                    int nack, int hmac)
{
    uint8_t name[128], content[64], payload[16] = "arm.state bytes";
    ln_ndn_pull_content c;
    ln_ndn_data d;
    ln_ndn_signer s = {hmac ? LN_NDN_SIG_HMAC_SHA256 : LN_NDN_SIG_DIGEST_SHA256,
                       (const uint8_t*)"key",
                       3,
                       {NULL, 0}};
    int n = ln_ndn_name_from_uri(name, sizeof name, uri);
    if (seq)
        n = ln_ndn_name_append_seq(name, sizeof name, (size_t)n, seq);
    memset(&c, 0, sizeof c);
    c.latest_seq = latest;
    if (!nack) {
        c.publish_us = 1700000000000000ull + seq * 20000;
        c.period_us = 20000;
        c.payload.data = payload;
        c.payload.size = sizeof payload;
    }
    memset(&d, 0, sizeof d);
    d.name.data = name;
    d.name.size = (size_t)n;
    d.content.data = content;
    d.content.size = (size_t)ln_ndn_encode_pull_content(content, sizeof content, &c);
    d.content_type = nack ? LN_NDN_CONTENT_NACK : LN_NDN_CONTENT_BLOB;
    d.freshness_ms = nack ? 0 : 1000;
    n = ln_ndn_encode_data(out, cap, &d, &s);
    return n > 0 ? (size_t)n : 0;
}

static size_t interest(uint8_t* out, size_t cap, const char* uri, int sync)
{
    uint8_t name[128];
    ln_ndn_interest in;
    memset(&in, 0, sizeof in);
    in.name.data = name;
    in.name.size = (size_t)ln_ndn_name_from_uri(name, sizeof name, uri);
    in.nonce = 0x01020304;
    in.lifetime_ms = 100;
    in.can_be_prefix = in.must_be_fresh = (uint8_t)sync;
    in.has_hop_limit = 1;
    in.hop_limit = 8;
    int n = ln_ndn_encode_interest(out, cap, &in);
    return n > 0 ? (size_t)n : 0;
}

static size_t record(uint8_t* out, const uint8_t* packet, size_t n, uint8_t dt)
{
    out[0] = (uint8_t)(n >> 8);
    out[1] = (uint8_t)n;
    out[2] = dt;
    memcpy(out + 3, packet, n);
    return n + 3;
}

void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    static uint8_t in[4096];
    uint8_t p[512], lp[600];
    const ln_ndn_bytes token = {(const uint8_t*)"\xaa\xbb\xcc\xdd\x01\x02\x03\x04", 8};
    const ln_ndn_bytes none = {NULL, 0};
    size_t n, m;
    static const uint8_t modes[] = {0x00, 0x31, 0x0b, 0x4e};
    static const char* names[] = {"naive", "hardened", "window", "polling"};
    for (int k = 0; k < 4; k++) {
        size_t size = 0;
        in[size++] = modes[k];
        n = reply(p, sizeof p, TOPIC "/sync", 10, 10, 0, 0); /* sync reply */
        size += record(in + size, p, n, 5);
        for (uint64_t s = 11; s < 15; s++) { /* samples, one LP-wrapped with a PitToken */
            n = reply(p, sizeof p, TOPIC, s, s + (s == 13 ? 5 : 0), 0, s == 12);
            if (s == 14) {
                m = (size_t)ln_ndn_encode_lp(lp, sizeof lp, token, p, n);
                size += record(in + size, lp, m, 20);
            } else {
                size += record(in + size, p, n, 20);
            }
        }
        n = reply(p, sizeof p, TOPIC, 15, 40, 1, 0); /* a NACK with the latest */
        size += record(in + size, p, n, 150);
        n = interest(p, sizeof p, TOPIC "/seq=41", 0); /* an LP Nack of an Interest */
        m = (size_t)ln_ndn_encode_lp(lp + 9, sizeof lp - 9, none, p, n);
        memcpy(lp, "\x64\x00\xfd\x03\x20\x05\xfd\x03\x21\x01\x96", 11);
        memmove(lp + 11, lp + 9 + 2, m - 2); /* drop the inner LpPacket header */
        m = 11 + m - 2;
        lp[1] = (uint8_t)(m - 2);
        size += record(in + size, lp, m, 1);
        n = reply(p, sizeof p, "/ln/robot/other", 3, 3, 0, 0); /* another topic */
        size += record(in + size, p, n, 1);
        n = interest(p, sizeof p, TOPIC "/sync", 1); /* an Interest */
        size += record(in + size, p, n, 200);
        emit(names[k], in, size);
    }
    /* single packets */
    n = interest(p, sizeof p, TOPIC "/seq=1234", 0);
    emit("interest", p, n);
    n = interest(p, sizeof p, "/rt/cmd_vel/sync", 1);
    emit("sync_interest", p, n);
    n = reply(p, sizeof p, TOPIC "/sync", 7, 7, 0, 1);
    emit("data_hmac", p, n);
    n = reply(p, sizeof p, TOPIC, 3, 90, 1, 0);
    emit("nack", p, n);
    m = (size_t)ln_ndn_encode_lp(lp, sizeof lp, token, p, n);
    emit("lp_nack_data", lp, m);
}
