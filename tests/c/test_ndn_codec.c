/* test_ndn_codec.c — the NDN codec of libln_pull (ln/ndn.h): golden vectors of
 * dit_transport §3.6, VAR-NUMBER and NonNegativeInteger edges, truncation at every byte, the
 * evolvability (critical-bit) rule, the nesting limit, NDNLPv2 wrapping, names and URIs, a
 * seeded round-trip property loop, and SHA-256 (FIPS 180-4) / HMAC-SHA256 (RFC 4231). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <ln/ndn.h>

#include "ln_test.h"

static size_t unhex(const char* s, uint8_t* out)
{
    size_t n = 0;
    for (; s[0] && s[1]; s += 2) {
        unsigned v;
        sscanf(s, "%2x", &v);
        out[n++] = (uint8_t)v;
    }
    return n;
}

static int same(const uint8_t* a, size_t na, const uint8_t* b, size_t nb)
{
    return na == nb && (na == 0 || memcmp(a, b, na) == 0);
}

static int uri_is(ln_ndn_bytes name, const char* uri)
{
    char buf[256];
    return ln_ndn_name_to_uri(buf, sizeof buf, name) >= 0 && strcmp(buf, uri) == 0;
}

/* Golden vectors: the two Interests as python-ndn 0.5.2 encodes them (dit_transport §3.6),
 * and the 95-byte Data of §3.6 laid out as python-ndn lays it out (explicit ContentType 0)
 * with payload 00..17, its digest computed independently (Python's hashlib). */
#define GOLD_INTEREST "051c0711080272740807636d645f76656c3a0204d20a04010203040c0164"
#define GOLD_SYNC "05220713080272740807636d645f76656c080473796e63210012000a04010203040c0164"
#define GOLD_DATA                                                                                  \
    "065d0711080272740807636d645f76656c3a0204d21407180100190203e8151800010203040506070809"         \
    "0a0b0c0d0e0f101112131415161716031b010017201209acce45ef7fac036a0d57cf4ddfa4a2705526ad"         \
    "5aca2db9528c597bae7e45"
/* The same Data as our encoder writes it (ContentType BLOB omitted), digest from hashlib. */
#define OUR_DATA                                                                                   \
    "065a0711080272740807636d645f76656c3a0204d21404190203e8151800010203040506070809"               \
    "0a0b0c0d0e0f101112131415161716031b01001720b61930501be4a69bd020ead27f168ebdc929b8"             \
    "7a947a81660e76d1eb1570057b"

static void test_golden_interests(void)
{
    uint8_t gold[64], name[64], out[64];
    ln_ndn_interest in;
    ln_ndn_packet p;
    size_t n = unhex(GOLD_INTEREST, gold);
    int size;
    LN_CHECK_EQ(n, 30);
    LN_CHECK_EQ(ln_ndn_decode(gold, n, &p), LN_NDN_OK);
    LN_CHECK_EQ(p.type, LN_NDN_T_INTEREST);
    LN_CHECK_EQ(p.lp, 0);
    LN_CHECK(uri_is(p.interest.name, "/rt/cmd_vel/seq=1234"));
    LN_CHECK_EQ(p.interest.nonce, 0x01020304);
    LN_CHECK_EQ(p.interest.has_nonce, 1);
    LN_CHECK_EQ(p.interest.lifetime_ms, 100);
    LN_CHECK_EQ(p.interest.can_be_prefix, 0);
    LN_CHECK_EQ(p.interest.must_be_fresh, 0);

    size = ln_ndn_name_from_uri(name, sizeof name, "/rt/cmd_vel/seq=1234");
    LN_CHECK_EQ(size, 17);
    memset(&in, 0, sizeof in);
    in.name.data = name;
    in.name.size = (size_t)size;
    in.nonce = 0x01020304;
    in.lifetime_ms = 100;
    size = ln_ndn_encode_interest(out, sizeof out, &in);
    LN_CHECK(size > 0 && same(out, (size_t)size, gold, n));

    n = unhex(GOLD_SYNC, gold);
    LN_CHECK_EQ(n, 36);
    LN_CHECK_EQ(ln_ndn_decode(gold, n, &p), LN_NDN_OK);
    LN_CHECK(uri_is(p.interest.name, "/rt/cmd_vel/sync"));
    LN_CHECK_EQ(p.interest.can_be_prefix, 1);
    LN_CHECK_EQ(p.interest.must_be_fresh, 1);
    LN_CHECK_EQ(p.interest.lifetime_ms, 100);
    size = ln_ndn_name_from_uri(name, sizeof name, "/rt/cmd_vel/sync");
    in.name.size = (size_t)size;
    in.can_be_prefix = in.must_be_fresh = 1;
    size = ln_ndn_encode_interest(out, sizeof out, &in);
    LN_CHECK(size > 0 && same(out, (size_t)size, gold, n));
    /* the default lifetime is not written, and decodes back as 4000 */
    in.lifetime_ms = LN_NDN_DEFAULT_LIFETIME_MS;
    size = ln_ndn_encode_interest(out, sizeof out, &in);
    LN_CHECK_EQ(size, 33);
    LN_CHECK_EQ(ln_ndn_decode(out, (size_t)size, &p), LN_NDN_OK);
    LN_CHECK_EQ(p.interest.lifetime_ms, 4000);
}

static void test_golden_data(void)
{
    uint8_t gold[128], ours[128], name[64], payload[24], out[128];
    ln_ndn_packet p;
    ln_ndn_data d;
    ln_ndn_signer digest = {LN_NDN_SIG_DIGEST_SHA256, NULL, 0, {NULL, 0}};
    size_t n = unhex(GOLD_DATA, gold), m = unhex(OUR_DATA, ours);
    int size;
    LN_CHECK_EQ(n, 95);
    LN_CHECK_EQ(ln_ndn_decode(gold, n, &p), LN_NDN_OK);
    LN_CHECK_EQ(p.type, LN_NDN_T_DATA);
    LN_CHECK(uri_is(p.data.name, "/rt/cmd_vel/seq=1234"));
    LN_CHECK_EQ(p.data.content_type, LN_NDN_CONTENT_BLOB);
    LN_CHECK_EQ(p.data.freshness_ms, 1000);
    for (int i = 0; i < 24; i++)
        payload[i] = (uint8_t)i;
    LN_CHECK(same(p.data.content.data, p.data.content.size, payload, 24));
    LN_CHECK_EQ(p.data.signature_type, LN_NDN_SIG_DIGEST_SHA256);
    LN_CHECK_EQ(p.data.signature_value.size, 32);
    LN_CHECK_EQ(p.data.signed_portion.size, 95 - 2 - 34);
    LN_CHECK_EQ(ln_ndn_verify(&p.data, &digest), LN_NDN_OK);
    gold[40] ^= 1; /* one payload bit: the digest no longer verifies */
    LN_CHECK_EQ(ln_ndn_decode(gold, n, &p), LN_NDN_OK);
    LN_CHECK_EQ(ln_ndn_verify(&p.data, &digest), LN_NDN_ESIGNATURE);

    size = ln_ndn_name_from_uri(name, sizeof name, "/rt/cmd_vel/seq=1234");
    memset(&d, 0, sizeof d);
    d.name.data = name;
    d.name.size = (size_t)size;
    d.freshness_ms = 1000;
    d.content.data = payload;
    d.content.size = 24;
    size = ln_ndn_encode_data(out, sizeof out, &d, &digest);
    LN_CHECK(size > 0 && same(out, (size_t)size, ours, m));
    LN_CHECK_EQ(ln_ndn_encode_data(out, (size_t)size - 1, &d, &digest), LN_NDN_ESPACE);
}

static void test_varnum_edges(void)
{
    static uint8_t big[65536 + 16], value[65536];
    static const struct {
        uint64_t v;
        const char* hex;
    } cases[] = {{0, "00"},
                 {252, "fc"},
                 {253, "fd00fd"},
                 {65535, "fdffff"},
                 {65536, "fe00010000"},
                 {0xffffffffu, "feffffffff"},
                 {0x100000000ull, "ff0000000100000000"}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        uint8_t b[16];
        size_t n = unhex(cases[i].hex, b), pos = 0;
        uint64_t v = 1;
        LN_CHECK_EQ(ln_ndn_read_varnum(b, n, &pos, &v), LN_NDN_OK);
        LN_CHECK_EQ(pos, n);
        LN_CHECK(v == cases[i].v);
        for (size_t cut = 0; cut < n; cut++) { /* cut off: nothing read, position kept */
            pos = 0;
            LN_CHECK_EQ(ln_ndn_read_varnum(b, cut, &pos, &v), LN_NDN_ETRUNCATED);
            LN_CHECK_EQ(pos, 0);
        }
    }
    /* TLV lengths across the edges: header sizes 1+1, 1+3, 1+3, 1+5 */
    static const size_t lengths[] = {252, 253, 65535, 65536};
    static const size_t heads[] = {2, 4, 4, 6};
    for (size_t i = 0; i < 4; i++) {
        ln_ndn_bytes content, rest;
        ln_ndn_pull_content c;
        int size = ln_ndn_write_tlv(big, sizeof big, LN_NDN_T_PULL_PAYLOAD, value, lengths[i]);
        LN_CHECK_EQ(size, (int)(heads[i] + lengths[i]));
        content.data = big;
        content.size = (size_t)size;
        LN_CHECK_EQ(ln_ndn_decode_pull_content(content, &c), LN_NDN_OK);
        LN_CHECK_EQ(c.payload.size, lengths[i]);
        LN_CHECK(c.payload.data == big + heads[i]);
        LN_CHECK_EQ(ln_ndn_write_tlv(big, heads[i] + lengths[i] - 1, 0x86, value, lengths[i]),
                    LN_NDN_ESPACE);
        rest = content;
        rest.size--; /* one byte short */
        LN_CHECK_EQ(ln_ndn_decode_pull_content(rest, &c), LN_NDN_ETRUNCATED);
    }
    /* a type number of 253 and above takes three bytes */
    uint8_t b[8];
    LN_CHECK_EQ(ln_ndn_write_tlv(b, sizeof b, 0x0320, NULL, 0), 4);
    LN_CHECK(b[0] == 0xfd && b[1] == 0x03 && b[2] == 0x20 && b[3] == 0);
}

static void test_nonneg(void)
{
    uint8_t b[16], want[16];
    uint64_t v;
    ln_ndn_bytes x;
    LN_CHECK_EQ(ln_ndn_write_nonneg_tlv(b, sizeof b, 0x80, 255), 3);
    LN_CHECK(same(b, 3, want, unhex("8001ff", want)));
    LN_CHECK_EQ(ln_ndn_write_nonneg_tlv(b, sizeof b, 0x80, 256), 4);
    LN_CHECK(same(b, 4, want, unhex("80020100", want)));
    LN_CHECK_EQ(ln_ndn_write_nonneg_tlv(b, sizeof b, 0x80, 65536), 6);
    LN_CHECK(same(b, 6, want, unhex("800400010000", want)));
    LN_CHECK_EQ(ln_ndn_write_nonneg_tlv(b, sizeof b, 0x80, 0x100000000ull), 10);
    LN_CHECK(same(b, 10, want, unhex("80080000000100000000", want)));
    LN_CHECK_EQ(ln_ndn_write_nonneg_tlv(b, 9, 0x80, 0x100000000ull), LN_NDN_ESPACE);
    x.data = want;
    for (size_t n = 0; n <= 9; n++) {
        x.size = n;
        int ok = n == 1 || n == 2 || n == 4 || n == 8;
        LN_CHECK_EQ(ln_ndn_read_nonneg(x, &v), ok ? LN_NDN_OK : LN_NDN_EMALFORMED);
    }
}

/* Every proper prefix of a valid packet is refused, read from a buffer of exactly that size
 * (the sanitizer build catches any read beyond it). */
static void check_truncations(const uint8_t* packet, size_t n)
{
    ln_ndn_packet p;
    LN_CHECK_EQ(ln_ndn_decode(packet, n, &p), LN_NDN_OK);
    for (size_t cut = 0; cut < n; cut++) {
        uint8_t* copy = malloc(cut ? cut : 1);
        memcpy(copy, packet, cut);
        int r = ln_ndn_decode(copy, cut, &p);
        if (r >= 0)
            fprintf(stderr, "    prefix of %zu/%zu bytes decoded\n", cut, n);
        LN_CHECK(r < 0);
        free(copy);
    }
}

static void test_truncation(void)
{
    uint8_t b[256], lp[300];
    size_t n;
    int m;
    ln_ndn_bytes token = {(const uint8_t*)"\x01\x02\x03\x04\x05\x06\x07\x08", 8};
    n = unhex(GOLD_INTEREST, b);
    check_truncations(b, n);
    m = ln_ndn_encode_lp(lp, sizeof lp, token, b, n);
    LN_CHECK(m > 0);
    check_truncations(lp, (size_t)m);
    n = unhex(GOLD_SYNC, b);
    check_truncations(b, n);
    n = unhex(GOLD_DATA, b);
    check_truncations(b, n);
    m = ln_ndn_encode_lp(lp, sizeof lp, token, b, n);
    check_truncations(lp, (size_t)m);
    /* trailing bytes after the packet are refused too */
    b[n] = 0;
    LN_CHECK_EQ(ln_ndn_decode(b, n + 1, &(ln_ndn_packet){0}), LN_NDN_EMALFORMED);
}

/* An Interest /a with `extra` (hex) between the Name and the Nonce, or after the Nonce. */
static int interest_with(const char* before_nonce, const char* after_nonce)
{
    char hex[256];
    uint8_t b[128];
    ln_ndn_packet p;
    snprintf(hex, sizeof hex, "0703080161%s0a0401020304%s", before_nonce, after_nonce);
    size_t n = unhex(hex, b + 2);
    b[0] = 0x05;
    b[1] = (uint8_t)n;
    return ln_ndn_decode(b, n + 2, &p);
}

static void test_critical_rule(void)
{
    LN_CHECK_EQ(interest_with("", ""), LN_NDN_OK);
    LN_CHECK_EQ(interest_with("8000", ""), LN_NDN_OK);        /* unknown even: skipped */
    LN_CHECK_EQ(interest_with("8100", ""), LN_NDN_ECRITICAL); /* unknown odd */
    LN_CHECK_EQ(interest_with("1000", ""), LN_NDN_ECRITICAL); /* unknown below 32 */
    LN_CHECK_EQ(interest_with("fd01f400", ""), LN_NDN_OK);    /* 500, even */
    LN_CHECK_EQ(interest_with("fd01f500", ""), LN_NDN_ECRITICAL);
    LN_CHECK_EQ(interest_with("", "2100"), LN_NDN_ECRITICAL);         /* CanBePrefix out of order */
    LN_CHECK_EQ(interest_with("", "0c0164"), LN_NDN_OK);              /* in order */
    LN_CHECK_EQ(interest_with("", "0c01640c0164"), LN_NDN_ECRITICAL); /* repeated: critical */
    LN_CHECK_EQ(interest_with("", "220120220120"), LN_NDN_OK);        /* HopLimit twice: even */
    LN_CHECK_EQ(interest_with("", "0a0401020304"), LN_NDN_ECRITICAL); /* a second Nonce */
    LN_CHECK_EQ(interest_with("", "0c0300000a"), LN_NDN_EMALFORMED);  /* 3-byte integer */
    LN_CHECK_EQ(interest_with("2101ff", ""), LN_NDN_EMALFORMED);      /* a flag with a value */
    /* an Interest without a Name, and with an empty Name */
    uint8_t b[16];
    ln_ndn_packet p;
    LN_CHECK_EQ(ln_ndn_decode(b, unhex("05060a0401020304", b), &p), LN_NDN_EMALFORMED);
    LN_CHECK_EQ(ln_ndn_decode(b, unhex("05080700 0a0401020304", b), &p), LN_NDN_EMALFORMED);
    /* a name component of type 0 */
    LN_CHECK_EQ(ln_ndn_decode(b, unhex("05050703000161", b), &p), LN_NDN_EMALFORMED);
    /* neither Interest nor Data */
    LN_CHECK_EQ(ln_ndn_decode(b, unhex("07030801ff", b), &p), LN_NDN_EUNSUPPORTED);
    /* Data: unknown critical element in MetaInfo and in SignatureInfo, a missing signature */
    uint8_t d[128];
    size_t n = unhex("06160703080161"
                     "14038101ff"
                     "150161"
                     "16031b0100"
                     "1700",
                     d);
    d[1] = (uint8_t)(n - 2);
    LN_CHECK_EQ(ln_ndn_decode(d, n, &p), LN_NDN_ECRITICAL);
    d[7 + 2] = 0x80; /* 0x81 -> 0x80: skipped */
    LN_CHECK_EQ(ln_ndn_decode(d, n, &p), LN_NDN_OK);
    n = unhex("06110703080161"
              "150161"
              "16031b0100",
              d); /* no SignatureValue */
    d[1] = (uint8_t)(n - 2);
    LN_CHECK_EQ(ln_ndn_decode(d, n, &p), LN_NDN_EMALFORMED);
    n = unhex("06110703080161"
              "150161"
              "1603810100"
              "1700",
              d); /* no SignatureType */
    d[1] = (uint8_t)(n - 2);
    LN_CHECK_EQ(ln_ndn_decode(d, n, &p), LN_NDN_ECRITICAL);
    /* pull content: unknown even skipped, odd critical */
    ln_ndn_pull_content c;
    ln_ndn_bytes x = {d, unhex("800107"
                               "880100"
                               "86026869",
                               d)};
    LN_CHECK_EQ(ln_ndn_decode_pull_content(x, &c), LN_NDN_OK);
    LN_CHECK_EQ(c.latest_seq, 7);
    LN_CHECK_EQ(c.payload.size, 2);
    x.size = unhex("800107"
                   "870100"
                   "86026869",
                   d);
    LN_CHECK_EQ(ln_ndn_decode_pull_content(x, &c), LN_NDN_ECRITICAL);
    LN_CHECK_EQ(c.latest_seq, 0);
}

static void test_nesting_limit(void)
{
    uint8_t b[512], gold[64], name[32];
    ln_ndn_packet p;
    ln_ndn_bytes none = {NULL, 0};
    size_t n = unhex(GOLD_INTEREST, gold);
    int size = (int)n;
    memcpy(b, gold, n);
    /* levels: LpPacket 1, its Fragment 2, the packet inside 3, ...: three LP layers put the
     * Interest at level 7 and its fields at 8, four at 9 — beyond LN_NDN_MAX_DEPTH */
    for (int wraps = 1; wraps <= 4; wraps++) {
        size = ln_ndn_encode_lp(b, sizeof b, none, b, (size_t)size);
        LN_CHECK(size > 0);
        LN_CHECK_EQ(ln_ndn_decode(b, (size_t)size, &p), wraps <= 3 ? LN_NDN_OK : LN_NDN_EDEPTH);
    }
    /* a Data's MetaInfo is one level deeper: three layers are too many for it */
    ln_ndn_data d;
    ln_ndn_signer s = {LN_NDN_SIG_DIGEST_SHA256, NULL, 0, {NULL, 0}};
    memset(&d, 0, sizeof d);
    d.name.data = name;
    d.name.size = (size_t)ln_ndn_name_from_uri(name, sizeof name, "/a");
    d.freshness_ms = 5;
    size = ln_ndn_encode_data(b, sizeof b, &d, &s);
    for (int wraps = 1; wraps <= 3; wraps++) {
        size = ln_ndn_encode_lp(b, sizeof b, none, b, (size_t)size);
        LN_CHECK_EQ(ln_ndn_decode(b, (size_t)size, &p), wraps <= 2 ? LN_NDN_OK : LN_NDN_EDEPTH);
    }
    LN_CHECK_EQ(LN_NDN_MAX_DEPTH, 8);
}

static void test_lp(void)
{
    uint8_t b[256], lp[256];
    ln_ndn_packet p;
    const uint8_t tok[] = {9, 8, 7, 6, 5, 4, 3, 2};
    ln_ndn_bytes token = {tok, sizeof tok};
    size_t n = unhex(GOLD_INTEREST, b);
    int size = ln_ndn_encode_lp(lp, sizeof lp, token, b, n);
    LN_CHECK_EQ(size, (int)(2 + 10 + 2 + n));
    LN_CHECK_EQ(lp[0], 0x64);
    LN_CHECK_EQ(ln_ndn_decode(lp, (size_t)size, &p), LN_NDN_OK);
    LN_CHECK_EQ(p.lp, 1);
    LN_CHECK_EQ(p.lp_nack, 0);
    LN_CHECK(same(p.pit_token.data, p.pit_token.size, tok, sizeof tok));
    LN_CHECK_EQ(p.type, LN_NDN_T_INTEREST);
    LN_CHECK(uri_is(p.interest.name, "/rt/cmd_vel/seq=1234"));
    LN_CHECK_EQ(ln_ndn_encode_lp(lp, (size_t)size - 1, token, b, n), LN_NDN_ESPACE);
    /* in place: the packet already in the output buffer */
    memcpy(lp + 40, b, n);
    size = ln_ndn_encode_lp(lp, sizeof lp, token, lp + 40, n);
    LN_CHECK_EQ(ln_ndn_decode(lp, (size_t)size, &p), LN_NDN_OK);
    LN_CHECK_EQ(p.interest.nonce, 0x01020304);

    /* Nack header with reason NoRoute (150); unknown ignorable header TxSequence 0x0348 */
    char hex[200];
    snprintf(hex, sizeof hex,
             "64%02x"
             "fd0348020001"
             "fd032005fd03210196"
             "50%02x" GOLD_INTEREST,
             (unsigned)(6 + 9 + 2 + n), (unsigned)n);
    size = (int)unhex(hex, lp);
    LN_CHECK_EQ(ln_ndn_decode(lp, (size_t)size, &p), LN_NDN_OK);
    LN_CHECK_EQ(p.lp_nack, 1);
    LN_CHECK_EQ(p.nack_reason, 150);
    LN_CHECK_EQ(p.interest.nonce, 0x01020304);
    lp[4] = 0x49; /* 0x0349: not ignorable */
    LN_CHECK_EQ(ln_ndn_decode(lp, (size_t)size, &p), LN_NDN_ECRITICAL);
    lp[3] = 0x02, lp[4] = 0xf4; /* 0x02f4 = 756, below 800 */
    LN_CHECK_EQ(ln_ndn_decode(lp, (size_t)size, &p), LN_NDN_ECRITICAL);
    /* a Nack around Data; an LpPacket with no Fragment; two fragments needed */
    n = unhex(GOLD_DATA, b);
    snprintf(hex, sizeof hex,
             "64%02x"
             "fd032000"
             "50%02x",
             (unsigned)(4 + 2 + n), (unsigned)n);
    size = (int)unhex(hex, lp);
    memcpy(lp + size, b, n);
    LN_CHECK_EQ(ln_ndn_decode(lp, (size_t)size + n, &p), LN_NDN_EMALFORMED);
    LN_CHECK_EQ(ln_ndn_decode(lp, unhex("6403510100", lp), &p), LN_NDN_EUNSUPPORTED);
    n = unhex(GOLD_INTEREST, b);
    snprintf(hex, sizeof hex,
             "64%02x"
             "530102"
             "50%02x" GOLD_INTEREST,
             (unsigned)(3 + 2 + n), (unsigned)n);
    LN_CHECK_EQ(ln_ndn_decode(lp, unhex(hex, lp), &p), LN_NDN_EUNSUPPORTED);
}

static void test_names(void)
{
    uint8_t b[128];
    char uri[128];
    ln_ndn_bytes name, prefix;
    ln_ndn_component c;
    int n;
    static const char* bad[] = {"",        "a",       "//",
                                "/a//b",   "/%zz",    "/%4",
                                "/seq=",   "/seq=x1", "/seq=18446744073709551616",
                                "/..",     "/a b",    "/0=x",
                                "/65536=x"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        if (ln_ndn_name_from_uri(b, sizeof b, bad[i]) != LN_NDN_ENAME)
            fprintf(stderr, "    accepted: \"%s\"\n", bad[i]);
        LN_CHECK_EQ(ln_ndn_name_from_uri(b, sizeof b, bad[i]), LN_NDN_ENAME);
    }
    LN_CHECK_EQ(ln_ndn_name_from_uri(b, sizeof b, "/"), 0);
    name.data = b;
    name.size = 0;
    LN_CHECK(uri_is(name, "/"));
    static const struct {
        const char *in, *out;
    } good[] = {{"/ln/robot/arm.state", "/ln/robot/arm.state"},
                {"ndn:/a/b/", "/a/b"},
                {"/a%2Fb/%41", "/a%2Fb/A"},
                {"/.../..../x", "/.../..../x"},
                {"/seq=0/seq=18446744073709551615", "/seq=0/seq=18446744073709551615"},
                {"/8=x/300=%00%ff/a=b", "/x/300=%00%FF/a%3Db"},
                {"/58=%01%02%03", "/58=%01%02%03"}}; /* a 3-byte seq is not a number */
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        n = ln_ndn_name_from_uri(b, sizeof b, good[i].in);
        LN_CHECK(n > 0);
        name.size = n > 0 ? (size_t)n : 0;
        LN_CHECK_EQ(ln_ndn_name_to_uri(uri, sizeof uri, name), (int)strlen(good[i].out));
        LN_CHECK_STREQ(uri, good[i].out);
    }
    n = ln_ndn_name_from_uri(b, sizeof b, "/ln/robot/arm.state/seq=42");
    LN_CHECK_EQ(n, 4 + 7 + 11 + 3);
    name.size = (size_t)n;
    LN_CHECK_EQ(ln_ndn_name_to_uri(uri, 26, name), LN_NDN_ESPACE);
    LN_CHECK_EQ(ln_ndn_name_to_uri(uri, 27, name), 26);
    LN_CHECK_EQ(ln_ndn_name_from_uri(b, 24, "/ln/robot/arm.state/seq=42"), LN_NDN_ESPACE);
    /* components */
    ln_ndn_bytes rest = name;
    LN_CHECK_EQ(ln_ndn_name_next(&rest, &c), 1);
    LN_CHECK(c.type == LN_NDN_T_GENERIC &&
             same(c.value.data, c.value.size, (const uint8_t*)"ln", 2));
    LN_CHECK_EQ(ln_ndn_name_next(&rest, &c), 1);
    LN_CHECK_EQ(ln_ndn_name_next(&rest, &c), 1);
    LN_CHECK_EQ(ln_ndn_name_next(&rest, &c), 1);
    LN_CHECK(c.type == LN_NDN_T_SEQUENCE_NUM && c.value.size == 1 && c.value.data[0] == 42);
    LN_CHECK_EQ(ln_ndn_name_next(&rest, &c), 0);
    /* prefixes: whole components only */
    uint8_t pb[64];
    prefix.data = pb;
    prefix.size = (size_t)ln_ndn_name_from_uri(pb, sizeof pb, "/ln/robot");
    LN_CHECK_EQ(ln_ndn_name_has_prefix(name, prefix), 1);
    prefix.size = 0;
    LN_CHECK_EQ(ln_ndn_name_has_prefix(name, prefix), 1);
    prefix.size = (size_t)ln_ndn_name_from_uri(pb, sizeof pb, "/ln/rob");
    LN_CHECK_EQ(ln_ndn_name_has_prefix(name, prefix), 0);
    prefix.size = (size_t)ln_ndn_name_from_uri(pb, sizeof pb, "/ln/robot/arm.state/seq=42/x");
    LN_CHECK_EQ(ln_ndn_name_has_prefix(name, prefix), 0);
    prefix.size = (size_t)ln_ndn_name_from_uri(pb, sizeof pb, "/ln/robot");
    prefix.size--; /* a cut component is no prefix */
    LN_CHECK_EQ(ln_ndn_name_has_prefix(name, prefix), 0);
    /* append */
    n = ln_ndn_name_from_uri(b, sizeof b, "/t");
    n = ln_ndn_name_append_seq(b, sizeof b, (size_t)n, 256);
    LN_CHECK_EQ(n, 3 + 4);
    name.size = (size_t)n;
    LN_CHECK(uri_is(name, "/t/seq=256"));
    LN_CHECK_EQ(ln_ndn_name_append(b, 9, 7, LN_NDN_T_GENERIC, (const uint8_t*)"x", 1),
                LN_NDN_ESPACE);
    LN_CHECK_EQ(ln_ndn_name_append(b, 10, 7, LN_NDN_T_GENERIC, (const uint8_t*)"x", 1), 10);
    LN_CHECK_EQ(ln_ndn_name_append(b, 64, 7, 0, NULL, 0), LN_NDN_ENAME);
    LN_CHECK_EQ(ln_ndn_name_append(b, 64, 7, 0x10000, NULL, 0), LN_NDN_ENAME);
}

/* ---- round-trip property -------------------------------------------------------------------- */
static uint32_t rng = 12345;
static uint32_t rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

static size_t random_name(uint8_t* b, size_t cap)
{
    static const uint32_t types[] = {
        LN_NDN_T_GENERIC, LN_NDN_T_GENERIC, LN_NDN_T_SEQUENCE_NUM, 1, 2, 0x32, 0xfd, 0xffff};
    size_t size = 0;
    int parts = 1 + (int)(rnd() % 5), r;
    for (int i = 0; i < parts; i++, size = r < 0 ? size : (size_t)r) { /* full: stop growing */
        uint32_t type = types[rnd() % 8];
        if (type == LN_NDN_T_SEQUENCE_NUM) {
            uint64_t seq = rnd();
            seq = (seq << (rnd() % 33)) ^ rnd();
            r = ln_ndn_name_append_seq(b, cap, size, seq);
        } else {
            uint8_t v[12];
            size_t n = rnd() % sizeof v;
            for (size_t j = 0; j < n; j++) /* periods often, to reach the "..." rule */
                v[j] = rnd() % 3 == 0 ? '.' : (uint8_t)rnd();
            r = ln_ndn_name_append(b, cap, size, type, v, n);
        }
    }
    return size;
}

static void test_round_trip(void)
{
    for (int round = 0; round < 2000; round++) {
        uint8_t name[128], again[128], out[512], content[200], key[80], keyname[40];
        char uri[600];
        ln_ndn_packet p;
        ln_ndn_bytes nb = {name, random_name(name, sizeof name)};
        /* URI round trip */
        int n = ln_ndn_name_to_uri(uri, sizeof uri, nb);
        LN_CHECK(n > 0);
        LN_CHECK(
            same(again, (size_t)ln_ndn_name_from_uri(again, sizeof again, uri), name, nb.size));
        /* Interest */
        ln_ndn_interest in;
        memset(&in, 0, sizeof in);
        in.name = nb;
        in.nonce = rnd();
        in.lifetime_ms = rnd() % 4 ? rnd() % 70000 : (rnd() % 2 ? 0xffffffffu : 4000);
        in.can_be_prefix = rnd() & 1;
        in.must_be_fresh = rnd() & 1;
        in.has_hop_limit = rnd() & 1;
        in.hop_limit = in.has_hop_limit ? (uint8_t)rnd() : 0;
        n = ln_ndn_encode_interest(out, sizeof out, &in);
        LN_CHECK(n > 0);
        LN_CHECK_EQ(ln_ndn_decode(out, (size_t)n, &p), LN_NDN_OK);
        LN_CHECK(same(p.interest.name.data, p.interest.name.size, name, nb.size));
        LN_CHECK(p.interest.nonce == in.nonce && p.interest.has_nonce);
        LN_CHECK(p.interest.lifetime_ms == in.lifetime_ms);
        LN_CHECK(p.interest.can_be_prefix == in.can_be_prefix &&
                 p.interest.must_be_fresh == in.must_be_fresh &&
                 p.interest.has_hop_limit == in.has_hop_limit &&
                 p.interest.hop_limit == in.hop_limit);
        /* Data with pull content, both signatures */
        ln_ndn_pull_content pc, back;
        size_t payload = rnd() % 120;
        for (size_t j = 0; j < sizeof content; j++)
            content[j] = (uint8_t)rnd();
        memset(&pc, 0, sizeof pc);
        pc.latest_seq = rnd() % 3 ? rnd() : 0;
        pc.publish_us = rnd() % 2 ? (uint64_t)rnd() << 20 : 0;
        pc.period_us = rnd() % 2 ? rnd() % 100000 : 0;
        if (rnd() % 4) {
            pc.payload.data = content + 60;
            pc.payload.size = payload;
        }
        uint8_t cbuf[200];
        int cn = ln_ndn_encode_pull_content(cbuf, sizeof cbuf, &pc);
        LN_CHECK(cn > 0);
        ln_ndn_bytes cb = {cbuf, (size_t)cn};
        LN_CHECK_EQ(ln_ndn_decode_pull_content(cb, &back), LN_NDN_OK);
        LN_CHECK(back.latest_seq == pc.latest_seq && back.publish_us == pc.publish_us &&
                 back.period_us == pc.period_us &&
                 same(back.payload.data, back.payload.size, pc.payload.data, pc.payload.size) &&
                 (back.payload.data != NULL) == (pc.payload.data != NULL));
        ln_ndn_data d;
        ln_ndn_signer s;
        memset(&d, 0, sizeof d);
        memset(&s, 0, sizeof s);
        d.name = nb;
        d.content = cb;
        d.content_type = rnd() % 3 ? 0 : rnd() % 2 ? 3 : rnd();
        d.freshness_ms = rnd() % 2 ? rnd() : 0;
        if (rnd() % 2) {
            s.type = LN_NDN_SIG_HMAC_SHA256;
            s.key = key;
            s.key_size = rnd() % sizeof key;
            for (size_t j = 0; j < s.key_size; j++)
                key[j] = (uint8_t)rnd();
            if (rnd() % 2) {
                s.key_name.data = keyname;
                s.key_name.size = random_name(keyname, sizeof keyname);
            }
        }
        n = ln_ndn_encode_data(out, sizeof out, &d, &s);
        if (n <= 0)
            fprintf(stderr, "    encode_data: %d\n", n);
        LN_CHECK(n > 0);
        if (n <= 0)
            continue;
        LN_CHECK_EQ(ln_ndn_decode(out, (size_t)n, &p), LN_NDN_OK);
        LN_CHECK(same(p.data.name.data, p.data.name.size, name, nb.size));
        LN_CHECK(same(p.data.content.data, p.data.content.size, cbuf, (size_t)cn));
        LN_CHECK(p.data.content_type == d.content_type && p.data.freshness_ms == d.freshness_ms);
        LN_CHECK(p.data.signature_type == s.type);
        LN_CHECK_EQ(ln_ndn_verify(&p.data, &s), LN_NDN_OK);
        if (s.key_name.size) {
            ln_ndn_bytes kl = p.data.key_locator, kn;
            LN_CHECK(kl.size == s.key_name.size + 2 && kl.data[0] == LN_NDN_T_NAME);
            kn.data = kl.data + 2;
            kn.size = kl.size - 2;
            LN_CHECK(same(kn.data, kn.size, keyname, s.key_name.size));
        } else {
            LN_CHECK_EQ(p.data.key_locator.size, 0);
        }
        if (s.type == LN_NDN_SIG_HMAC_SHA256) { /* another key does not verify */
            ln_ndn_signer other = s;
            uint8_t k2[80];
            memcpy(k2, key, sizeof k2);
            k2[0] ^= 0x80;
            other.key = k2;
            other.key_size = s.key_size ? s.key_size : 1;
            LN_CHECK_EQ(ln_ndn_verify(&p.data, &other), LN_NDN_ESIGNATURE);
        }
        /* one flipped bit anywhere: refused by the decoder or by the signature */
        size_t bit = rnd() % ((size_t)n * 8);
        out[bit / 8] ^= (uint8_t)(1u << (bit % 8));
        LN_CHECK(ln_ndn_decode(out, (size_t)n, &p) < 0 || ln_ndn_verify(&p.data, &s) < 0 ||
                 bit / 8 < 2 /* the outer length: may still decode */);
    }
}

/* ---- SHA-256 and HMAC ---------------------------------------------------------------------- */
static int digest_is(const uint8_t d[32], const char* hex)
{
    uint8_t want[32];
    return unhex(hex, want) == 32 && memcmp(d, want, 32) == 0;
}

static void test_sha256(void)
{
    ln_ndn_sha256 s;
    uint8_t d[32], a[1001];
    ln_ndn_sha256_init(&s);
    ln_ndn_sha256_final(&s, d);
    LN_CHECK(digest_is(d, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"));
    ln_ndn_sha256_init(&s);
    ln_ndn_sha256_update(&s, "abc", 3);
    ln_ndn_sha256_final(&s, d);
    LN_CHECK(digest_is(d, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"));
    ln_ndn_sha256_init(&s);
    ln_ndn_sha256_update(&s, "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq", 56);
    ln_ndn_sha256_final(&s, d);
    LN_CHECK(digest_is(d, "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"));
    memset(a, 'a', sizeof a);
    ln_ndn_sha256_init(&s);
    for (int i = 0; i < 1000; i++) /* one million 'a', in pieces that straddle blocks */
        ln_ndn_sha256_update(&s, a, i % 2 ? 999 : 1001);
    ln_ndn_sha256_final(&s, d);
    LN_CHECK(digest_is(d, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"));
}

static void test_hmac_rfc4231(void)
{
    uint8_t key[131], data[160], d[32];
    /* case 1 */
    memset(key, 0x0b, 20);
    ln_ndn_hmac_sha256(key, 20, "Hi There", 8, d);
    LN_CHECK(digest_is(d, "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7"));
    /* case 2 */
    ln_ndn_hmac_sha256((const uint8_t*)"Jefe", 4, "what do ya want for nothing?", 28, d);
    LN_CHECK(digest_is(d, "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"));
    /* case 3 */
    memset(key, 0xaa, 20);
    memset(data, 0xdd, 50);
    ln_ndn_hmac_sha256(key, 20, data, 50, d);
    LN_CHECK(digest_is(d, "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe"));
    /* case 4 */
    for (int i = 0; i < 25; i++)
        key[i] = (uint8_t)(i + 1);
    memset(data, 0xcd, 50);
    ln_ndn_hmac_sha256(key, 25, data, 50, d);
    LN_CHECK(digest_is(d, "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b"));
    /* case 6 */
    memset(key, 0xaa, 131);
    static const char m6[] = "Test Using Larger Than Block-Size Key - Hash Key First";
    ln_ndn_hmac_sha256(key, 131, m6, sizeof m6 - 1, d);
    LN_CHECK(digest_is(d, "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54"));
    /* case 7 */
    static const char m7[] = "This is a test using a larger than block-size key and a larger "
                             "than block-size data. The key needs to be hashed before being "
                             "used by the HMAC algorithm.";
    ln_ndn_hmac_sha256(key, 131, m7, sizeof m7 - 1, d);
    LN_CHECK(digest_is(d, "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2"));
}

static void test_strerror(void)
{
#define CHECK_TEXT(name, code, text) LN_CHECK_STREQ(ln_ndn_strerror(code), text);
    LN_NDN_ERRNO_MAP(CHECK_TEXT)
#undef CHECK_TEXT
    LN_CHECK_STREQ(ln_ndn_strerror(-1000), "unknown error");
    LN_CHECK_STREQ(ln_ndn_strerror(LN_NDN_OK), "success");
}

int main(void)
{
    LN_TEST_RUN(test_golden_interests);
    LN_TEST_RUN(test_golden_data);
    LN_TEST_RUN(test_varnum_edges);
    LN_TEST_RUN(test_nonneg);
    LN_TEST_RUN(test_truncation);
    LN_TEST_RUN(test_critical_rule);
    LN_TEST_RUN(test_nesting_limit);
    LN_TEST_RUN(test_lp);
    LN_TEST_RUN(test_names);
    LN_TEST_RUN(test_round_trip);
    LN_TEST_RUN(test_sha256);
    LN_TEST_RUN(test_hmac_rfc4231);
    LN_TEST_RUN(test_strerror);
    LN_TEST_EXIT();
}
