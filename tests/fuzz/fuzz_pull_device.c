/* fuzz_pull_device.c — fuzz target: the device build of libln_pull's consumer (its own
 * objects of pull_dit.c, pull_decode.c and sha256.c compiled with -DLN_PULL_NO_URI
 * -DLN_NDN_CONSUMER -DLN_PULL_HMAC) with a differential oracle against the generic decoder
 * of libln_pull.a.  The input is one packet.  The oracle, exactly:
 *  - ln_ndn_i_decode_reply (compact) and ln_ndn_decode (generic) return the same code: the
 *    same packets accepted, the same error for those refused;
 *  - when accepted, the same packet type and the same views (pointer and size into the
 *    input) of the Name and, for an Interest, the same Nack flag and Nonce; for a Data, the
 *    same Content, SignatureValue and signed portion views, ContentType and SignatureType;
 *  - the Name's components, taken one by one with ln_ndn_i_component and ln_ndn_name_next,
 *    are the same (code, type, value view), and each SequenceNum reads the same with
 *    ln_ndn_i_nonneg and ln_ndn_read_nonneg;
 *  - a Data's Content decodes to the same code with ln_ndn_i_decode_content and
 *    ln_ndn_decode_pull_content and, when accepted, the same latest seq, publish time,
 *    period and payload view.
 * Then the packet goes to two device subscriptions to /ln/robot/arm.state, a hardened one and
 * a naive one verifying HMAC-SHA256 under a fixed key: neither may crash or break its
 * invariants, and the verifying one delivers only a Data that ln_ndn_verify accepts. */
#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "ln/pull.h"
#include "pull_internal.h"

#define TOPIC "/ln/robot/arm.state"
static const uint8_t KEY[16] = "fuzz-device-key";

static int same(ln_ndn_bytes a, ln_ndn_bytes b)
{
    return a.size == b.size && (a.size == 0 || a.data == b.data);
}

static void same_names(ln_ndn_bytes a, ln_ndn_bytes b)
{
    ln_ndn_component ca, cb;
    int ra, rb;
    do {
        ra = ln_ndn_i_component(&a, &ca);
        rb = ln_ndn_name_next(&b, &cb);
        assert(ra == rb);
        if (ra == 1) {
            assert(ca.type == cb.type && same(ca.value, cb.value));
            if (ca.type == LN_NDN_T_SEQUENCE_NUM) {
                uint64_t sa = 0, sb = 0;
                int na = ln_ndn_i_nonneg(&ca.value, &sa), nb = ln_ndn_read_nonneg(cb.value, &sb);
                assert(na == nb && (na < 0 || sa == sb));
                (void)na, (void)nb;
            }
        }
    } while (ra == 1);
}

static void same_content(ln_ndn_bytes content)
{
    ln_ndn_pull_content a, b;
    int ra = ln_ndn_i_decode_content(&content, &a), rb = ln_ndn_decode_pull_content(content, &b);
    assert(ra == rb);
    if (ra == LN_NDN_OK)
        assert(a.latest_seq == b.latest_seq && a.publish_us == b.publish_us &&
               a.period_us == b.period_us && same(a.payload, b.payload));
    (void)ra, (void)rb;
}

static void differential(const uint8_t* data, size_t size)
{
    ln_ndn_i_reply c;
    ln_ndn_packet g;
    int rc = ln_ndn_i_decode_reply(data, size, &c), rg = ln_ndn_decode(data, size, &g);
    assert(rc == rg);
    if (rc != LN_NDN_OK)
        return;
    assert(c.type == g.type);
    if (g.type == LN_NDN_T_INTEREST) {
        assert(same(c.name, g.interest.name) && c.lp_nack == g.lp_nack &&
               c.has_nonce == g.interest.has_nonce && c.nonce == g.interest.nonce);
        same_names(c.name, g.interest.name);
        return;
    }
    assert(same(c.name, g.data.name) && same(c.content, g.data.content) &&
           same(c.signature, g.data.signature_value) &&
           same(c.signed_portion, g.data.signed_portion) && c.content_type == g.data.content_type &&
           c.signature_type == g.data.signature_type && !c.lp_nack && !g.lp_nack);
    same_names(c.name, g.data.name);
    same_content(c.content);
}

static void sent(void* user, const uint8_t* packet, size_t size)
{
    ln_ndn_packet p;
    int rc = ln_ndn_decode(packet, size, &p);
    assert(rc == LN_NDN_OK && p.type == LN_NDN_T_INTEREST && size <= LN_PULL_TX_BYTES);
    (void)rc, (void)user;
}

/* The packet being fed: what the verifying subscription delivers must verify under KEY */
static const uint8_t* current;
static size_t current_size;

static void verified_only(void* user, uint64_t seq, const uint8_t* payload, size_t size,
                          uint64_t publish_us)
{
    ln_ndn_packet p;
    ln_ndn_signer hmac = {LN_NDN_SIG_HMAC_SHA256, KEY, sizeof KEY, {NULL, 0}};
    int rc = ln_ndn_decode(current, current_size, &p);
    assert(rc == LN_NDN_OK && p.type == LN_NDN_T_DATA &&
           ln_ndn_verify(&p.data, &hmac) == LN_NDN_OK);
    (void)rc, (void)user, (void)seq, (void)payload, (void)size, (void)publish_us;
}

static void check(const ln_pull_sub* s)
{
    for (int i = 0; i < LN_PULL_MAX_WINDOW; i++)
        for (int j = i + 1; j < LN_PULL_MAX_WINDOW; j++)
            assert(!s->slots[i].seq || s->slots[i].seq != s->slots[j].seq);
    assert(s->t_ms >= s->opt.t_min_ms && s->t_ms <= s->opt.t_max_ms);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static ln_pull_sub plain, verifying;
    static uint8_t name[LN_PULL_MAX_NAME];
    static int name_size;
    ln_pull_options o;
    uint8_t* packet = malloc(size ? size : 1); /* exactly size bytes: reads beyond are caught */
    if (!packet)
        return 0;
    memcpy(packet, data, size);
    differential(packet, size);
    if (!name_size)
        name_size = ln_ndn_name_from_uri(name, sizeof name, TOPIC);
    ln_pull_options_hardened(&o, 100);
    int rc = ln_pull_start_name(&plain, name, (size_t)name_size, &o, sent, NULL, NULL, NULL, 0, 1);
    assert(rc == LN_NDN_OK);
    ln_pull_options_naive(&o);
    rc = ln_pull_start_name(&verifying, name, (size_t)name_size, &o, sent, verified_only, NULL,
                            NULL, 0, 2);
    assert(rc == LN_NDN_OK && ln_pull_set_verify_key(&verifying, KEY, sizeof KEY) == LN_NDN_OK);
    (void)rc;
    current = packet;
    current_size = size;
    for (int i = 0; i < 2; i++) {
        ln_pull_sub* s = i ? &verifying : &plain;
        int r = ln_pull_receive(s, packet, size, 5);
        assert(r == 0 || r == 1 || (r < 0 && r >= LN_NDN_EDEPTH));
        check(s);
        ln_pull_poll(s, 5000);
        check(s);
    }
    free(packet);
    return 0;
}

/* ---- seeds, from the generic encoders ---------------------------------------------------- */
static size_t data_packet(uint8_t* out, size_t cap, const char* uri, uint64_t latest, int nack,
                          int hmac)
{
    uint8_t name[128], content[96], payload[16] = "arm.state bytes";
    ln_ndn_pull_content c;
    ln_ndn_data d;
    ln_ndn_signer s = {
        hmac ? LN_NDN_SIG_HMAC_SHA256 : LN_NDN_SIG_DIGEST_SHA256, KEY, sizeof KEY, {NULL, 0}};
    memset(&c, 0, sizeof c);
    memset(&d, 0, sizeof d);
    c.latest_seq = latest;
    if (!nack) {
        c.publish_us = 1700000000000000ull;
        c.period_us = 20000;
        c.payload.data = payload;
        c.payload.size = sizeof payload;
    }
    d.name.data = name;
    d.name.size = (size_t)ln_ndn_name_from_uri(name, sizeof name, uri);
    d.content.data = content;
    d.content.size = (size_t)ln_ndn_encode_pull_content(content, sizeof content, &c);
    d.content_type = nack ? LN_NDN_CONTENT_NACK : LN_NDN_CONTENT_BLOB;
    d.freshness_ms = nack ? 0 : 1000;
    int n = ln_ndn_encode_data(out, cap, &d, &s);
    return n > 0 ? (size_t)n : 0;
}

void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    uint8_t p[512], lp[600], in[200], name[128];
    const ln_ndn_bytes token = {(const uint8_t*)"\xaa\xbb\xcc\xdd", 4}, none = {NULL, 0};
    ln_ndn_interest it;
    size_t n, m;
    n = data_packet(p, sizeof p, TOPIC "/sync/seq=10", 10, 0, 0);
    emit("sync_reply", p, n);
    n = data_packet(p, sizeof p, TOPIC "/sync/seq=10", 10, 0, 1); /* delivered when verifying */
    emit("sync_reply_hmac", p, n);
    n = data_packet(p, sizeof p, TOPIC "/seq=11", 11, 0, 1);
    emit("sample_hmac", p, n);
    m = (size_t)ln_ndn_encode_lp(lp, sizeof lp, token, p, n);
    emit("sample_lp", lp, m);
    n = (size_t)ln_ndn_encode_lp(p, sizeof p, none, lp, m); /* LpPacket in an LpPacket */
    emit("sample_lp2", p, n);
    n = data_packet(p, sizeof p, TOPIC "/seq=3", 90, 1, 0);
    emit("nack", p, n);
    memset(&it, 0, sizeof it);
    it.name.data = name;
    it.name.size = (size_t)ln_ndn_name_from_uri(name, sizeof name, TOPIC "/seq=12");
    it.nonce = 0x01020304;
    it.lifetime_ms = 100;
    it.has_hop_limit = 1;
    it.hop_limit = 4;
    n = (size_t)ln_ndn_encode_interest(in, sizeof in, &it);
    emit("interest", in, n);
    /* an NDNLPv2 Nack (reason 150) of that Interest */
    memcpy(lp, "\x64\x00\xfd\x03\x20\x05\xfd\x03\x21\x01\x96\x50", 12);
    lp[12] = (uint8_t)n;
    memcpy(lp + 13, in, n);
    lp[1] = (uint8_t)(11 + n);
    emit("lp_nack", lp, 13 + n);
}
