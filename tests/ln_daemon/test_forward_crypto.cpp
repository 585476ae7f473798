// test_forward_crypto.cpp — the protection of forwarded data without sockets
// (forward_crypto.cpp, forward_tcp_frame.cpp): key derivation, sealing and opening with each
// suite, the same bytes as libsodium's reference constructions (the wire of daemons built
// either way), the replay window's edges, and the TCP handshake and frame checks.
#include <algorithm>
#include <cstring>
#include <sodium.h>
#include <vector>

#include "daemon_test.hpp"
#include "forward_crypto.hpp"
#include "forward_tcp_frame.hpp"
#include "forward_wire.hpp"

using namespace lnd::fwd;
using lnd::Key;
using sec::Box;
using sec::Level;
using sec::ReplayWindow;
using sec::Suite;

namespace {

Key key_of(uint8_t byte)
{
    Key k;
    std::memset(k.bytes, byte, Key::kBytes);
    return k;
}

bool same(const Key &a, const Key &b) { return std::memcmp(a.bytes, b.bytes, Key::kBytes) == 0; }

void test_key_derivation()
{
    Key a, b, c, d;
    sec::stream_key(key_of(1), 42, 0, a);
    sec::stream_key(key_of(1), 42, 0, b);
    LN_CHECK(same(a, b)); // both daemons derive the same key
    sec::stream_key(key_of(1), 43, 0, c);
    LN_CHECK(!same(a, c)); // another stream
    sec::stream_key(key_of(1), 42, 1, c);
    LN_CHECK(!same(a, c)); // another transport
    sec::stream_key(key_of(2), 42, 0, d);
    LN_CHECK(!same(a, d)); // another daemon key
    uint8_t salt1[8] = {1}, salt2[8] = {2};
    sec::sub_key(a, "udp salt", salt1, 8, c);
    sec::sub_key(a, "udp salt", salt2, 8, d);
    LN_CHECK(!same(c, d));
    sec::sub_key(a, "tcp connection", salt1, 8, d);
    LN_CHECK(!same(c, d)); // the label separates uses
}

void seal_and_open(Suite suite)
{
    Key k = key_of(7);
    Box box(k, suite);
    uint8_t head[64];
    for (size_t i = 0; i < sizeof head; ++i)
        head[i] = static_cast<uint8_t>(i);
    const char text[] = "joint positions of the left arm";
    std::vector<uint8_t> plain(text, text + sizeof text), wire(plain.size()), out(plain.size());
    uint8_t tag[sec::kTagBytes];
    uint8_t trailer[8] = {'L', 'N', 'F', 'E', 0, 0, 0, 0};
    box.seal(5, head, sizeof head, plain.data(), plain.size(), wire.data(), tag, trailer, 8);
    const bool encrypts = suite != Suite::poly1305;
    const uint8_t *sent = encrypts ? wire.data() : plain.data();
    if (encrypts)
        LN_CHECK(std::memcmp(wire.data(), plain.data(), plain.size()) != 0);
    LN_CHECK(box.open(5, head, sizeof head, sent, plain.size(), out.data(), tag, trailer, 8));
    if (encrypts)
        LN_CHECK(std::memcmp(out.data(), plain.data(), plain.size()) == 0);
    // Whatever changes, it does not open: counter, header, payload, trailer, tag, key.
    LN_CHECK(!box.open(6, head, sizeof head, sent, plain.size(), out.data(), tag, trailer, 8));
    head[9] ^= 1;
    LN_CHECK(!box.open(5, head, sizeof head, sent, plain.size(), out.data(), tag, trailer, 8));
    head[9] ^= 1;
    std::vector<uint8_t> bent(sent, sent + plain.size());
    bent[3] ^= 0x80;
    LN_CHECK(
        !box.open(5, head, sizeof head, bent.data(), bent.size(), out.data(), tag, trailer, 8));
    trailer[4] = 1;
    LN_CHECK(!box.open(5, head, sizeof head, sent, plain.size(), out.data(), tag, trailer, 8));
    trailer[4] = 0;
    tag[15] ^= 1;
    LN_CHECK(!box.open(5, head, sizeof head, sent, plain.size(), out.data(), tag, trailer, 8));
    tag[15] ^= 1;
    // Truncated: one byte less of payload.
    LN_CHECK(!box.open(5, head, sizeof head, sent, plain.size() - 1, out.data(), tag, trailer, 8));
    Box other(key_of(8), suite);
    LN_CHECK(!other.open(5, head, sizeof head, sent, plain.size(), out.data(), tag, trailer, 8));
    // In place, as the receivers do.
    std::vector<uint8_t> inplace(sent, sent + plain.size());
    LN_CHECK(box.open(5, head, sizeof head, inplace.data(), inplace.size(), inplace.data(), tag,
                      trailer, 8));
    if (encrypts)
        LN_CHECK(inplace == plain);
}

void put64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}

// What libsodium makes of one datagram or frame (the construction docs/security.md gives):
// the tag, and the cipher text in `out` for the AEAD suites.
void reference_seal(Suite suite, const Key &k, uint64_t counter, const std::vector<uint8_t> &ad,
                    const std::vector<uint8_t> &payload, const std::vector<uint8_t> &trailer,
                    std::vector<uint8_t> &out, uint8_t tag[sec::kTagBytes])
{
    uint8_t nonce[12] = {};
    put64(nonce, counter);
    out.assign(payload.size(), 0);
    uint8_t none = 0;
    const uint8_t *in = payload.empty() ? &none : payload.data();
    uint8_t *dst = out.empty() ? &none : out.data();
    if (suite == Suite::poly1305) {
        uint8_t one_time[crypto_onetimeauth_KEYBYTES];
        crypto_stream_chacha20_ietf(one_time, sizeof one_time, nonce, k.bytes);
        std::vector<uint8_t> all = ad;
        all.insert(all.end(), payload.begin(), payload.end());
        all.insert(all.end(), trailer.begin(), trailer.end());
        uint8_t lengths[24];
        put64(lengths, ad.size());
        put64(lengths + 8, payload.size());
        put64(lengths + 16, trailer.size());
        all.insert(all.end(), lengths, lengths + 24);
        crypto_onetimeauth(tag, all.data(), all.size(), one_time);
        return;
    }
    std::vector<uint8_t> all = ad;
    all.insert(all.end(), trailer.begin(), trailer.end());
    unsigned long long tag_len = 0;
    if (suite == Suite::chacha20poly1305)
        crypto_aead_chacha20poly1305_ietf_encrypt_detached(dst, tag, &tag_len, in, payload.size(),
                                                           all.data(), all.size(), nullptr, nonce,
                                                           k.bytes);
    else
        crypto_aead_aes256gcm_encrypt_detached(dst, tag, &tag_len, in, payload.size(), all.data(),
                                               all.size(), nullptr, nonce, k.bytes);
}

// Box seals every size as libsodium does, and opens what libsodium sealed: daemons whose
// forwarding crypto comes from either library understand each other.
void same_bytes_as_libsodium(Suite suite)
{
    Key k = key_of(0x5a);
    Box box(k, suite);
    const bool encrypts = suite != Suite::poly1305;
    for (size_t size : {size_t{0}, size_t{1}, size_t{15}, size_t{64}, size_t{1000}, size_t{65537},
                        size_t{1} << 20}) {
        std::vector<uint8_t> ad(40), payload(size), trailer(8), want, got(size), back(size);
        randombytes_buf(ad.data(), ad.size());
        if (size)
            randombytes_buf(payload.data(), size);
        randombytes_buf(trailer.data(), trailer.size());
        for (bool with_trailer : {false, true}) {
            const std::vector<uint8_t> tr = with_trailer ? trailer : std::vector<uint8_t>{};
            uint8_t want_tag[sec::kTagBytes], tag[sec::kTagBytes];
            const uint64_t counter = 1 + size;
            reference_seal(suite, k, counter, ad, payload, tr, want, want_tag);
            box.seal(counter, ad.data(), ad.size(), payload.data(), size, got.data(), tag,
                     tr.data(), tr.size());
            LN_CHECK(std::memcmp(tag, want_tag, sizeof tag) == 0);
            if (encrypts && size > 0)
                LN_CHECK(std::memcmp(got.data(), want.data(), size) == 0);
            const uint8_t *sent = encrypts ? want.data() : payload.data();
            LN_CHECK(box.open(counter, ad.data(), ad.size(), sent, size, back.data(), want_tag,
                              tr.data(), tr.size()));
            if (encrypts && size > 0)
                LN_CHECK(std::memcmp(back.data(), payload.data(), size) == 0);
        }
    }
}

void test_suites()
{
    seal_and_open(Suite::poly1305);
    seal_and_open(Suite::chacha20poly1305);
    seal_and_open(Suite::aes256gcm); // OpenSSL opens AES-GCM on every CPU
    same_bytes_as_libsodium(Suite::poly1305);
    same_bytes_as_libsodium(Suite::chacha20poly1305);
    if (crypto_aead_aes256gcm_is_available())
        same_bytes_as_libsodium(Suite::aes256gcm);
    LN_CHECK(sec::suite_accepted(Level::encrypt, Suite::aes256gcm));
    LN_CHECK(sec::suite_for(Level::none) == Suite::none);
    LN_CHECK(sec::suite_for(Level::authenticate) == Suite::poly1305);
    LN_CHECK(sec::suite_accepted(Level::encrypt, sec::suite_for(Level::encrypt)));
    LN_CHECK(sec::suite_accepted(Level::encrypt, Suite::chacha20poly1305));
    // No downgrade: a receiver takes only its own level's suites.
    LN_CHECK(!sec::suite_accepted(Level::encrypt, Suite::poly1305));
    LN_CHECK(!sec::suite_accepted(Level::authenticate, Suite::none));
    LN_CHECK(!sec::suite_accepted(Level::none, Suite::poly1305));
    LN_CHECK(!sec::suite_accepted(Level::authenticate, static_cast<Suite>(9)));
}

void test_replay_window()
{
    using V = ReplayWindow::Verdict;
    ReplayWindow w;
    LN_CHECK(w.check(0) == V::invalid);
    LN_CHECK(w.check(sec::kMaxCounter + 1) == V::invalid);
    LN_CHECK(w.check(1) == V::fresh);
    w.accept(1);
    LN_CHECK(w.check(1) == V::duplicate);
    w.accept(3); // 2 is late but within the window
    LN_CHECK(w.check(2) == V::fresh);
    w.accept(2);
    LN_CHECK(w.check(2) == V::duplicate);
    // The oldest counter the window still knows, and the first it does not.
    const uint64_t top = 10 * ReplayWindow::kBits + 17;
    w.accept(top); // far ahead: everything before is forgotten
    LN_CHECK_EQ(w.top(), top);
    LN_CHECK(w.check(top - ReplayWindow::kBits + 1) == V::fresh);
    LN_CHECK(w.check(top - ReplayWindow::kBits) == V::too_old);
    LN_CHECK(w.check(3) == V::too_old);
    // Bits of skipped counters whose slots a far jump reused are clear (the ring wrapped).
    for (uint64_t c = top - 5; c < top; ++c)
        LN_CHECK(w.check(c) == V::fresh);
    w.accept(top - 2);
    // Around a multiple of the window size (the ring's wrap).
    const uint64_t edge = 12 * ReplayWindow::kBits;
    for (uint64_t c = edge - 3; c <= edge + 3; ++c)
        w.accept(c);
    for (uint64_t c = edge - 3; c <= edge + 3; ++c)
        LN_CHECK(w.check(c) == V::duplicate);
    LN_CHECK(w.check(edge - 4) == V::fresh);     // skipped: may still come
    LN_CHECK(w.check(top - 2) == V::too_old);    // now out of the window
    w.accept(edge + ReplayWindow::kBits - 4);    // a jump of less than the window
    LN_CHECK(w.check(edge - 3) == V::duplicate); // still in the window, still seen
    LN_CHECK(w.check(edge - 4) == V::too_old);
    LN_CHECK(w.check(edge + 4) == V::fresh);
    LN_CHECK(w.check(sec::kMaxCounter) == V::fresh); // the last counter there is
    w.accept(sec::kMaxCounter);
    LN_CHECK(w.check(sec::kMaxCounter) == V::duplicate);
    w.reset();
    LN_CHECK(w.check(1) == V::fresh);
}

// The sender's hello and the receiver's judgement of it, then frames.
struct Handshake {
    Key stream;
    SendSpec spec;
    uint8_t hello[wire::kHelloSize];
    wire::Hello decoded;
    TcpSession session;
    uint8_t reply[wire::kReplySize];

    wire::Reject run(Level sender, Level receiver, const Key &receiver_key)
    {
        spec.token = 77;
        spec.message_size = 32;
        spec.layout_hash = 5;
        spec.transport = Transport::tcp;
        sec::stream_key(key_of(3), spec.token, 1, stream);
        uint8_t nonce[wire::kHandshakeNonce] = {9, 9, 9};
        encode_tcp_hello(spec, stream, sec::suite_for(sender), nonce, hello);
        LN_CHECK(wire::decode_hello(hello, decoded));
        Key theirs;
        sec::stream_key(receiver_key, spec.token, 1, theirs);
        HelloRules rules{32, 5, receiver, &theirs};
        uint8_t mine[wire::kHandshakeNonce] = {4, 4};
        return session.accept(decoded, hello, rules, mine, reply);
    }
};

std::vector<uint8_t> frame(sec::Box &box, uint64_t counter, uint64_t seq)
{
    std::vector<uint8_t> f(wire::kFrameHeaderSize + 32 + wire::kFrameTrailerSize + sec::kTagBytes);
    wire::encode_frame_header(f.data(), {seq, 1, 32});
    std::memset(f.data() + wire::kFrameHeaderSize, static_cast<int>(seq), 32);
    uint8_t *trailer = f.data() + wire::kFrameHeaderSize + 32;
    wire::encode_frame_trailer(trailer, true);
    box.seal(counter, f.data(), wire::kFrameHeaderSize, f.data() + wire::kFrameHeaderSize, 32,
             f.data() + wire::kFrameHeaderSize, trailer + wire::kFrameTrailerSize, trailer,
             wire::kFrameTrailerSize);
    return f;
}

TcpSession::Frame judge(TcpSession &s, std::vector<uint8_t> f)
{
    uint8_t *trailer = f.data() + wire::kFrameHeaderSize + 32;
    return s.frame(f.data(), f.data() + wire::kFrameHeaderSize, trailer,
                   trailer + wire::kFrameTrailerSize);
}

// The same, with the payload's tag computed while it "arrives": in pieces of `piece` bytes,
// the first `fed` of its 32 bytes (fewer than all: the frame judges the rest itself).
TcpSession::Frame judge_streamed(TcpSession &s, std::vector<uint8_t> f, size_t piece,
                                 size_t fed = 32)
{
    s.begin(f.data());
    for (size_t at = 0; at < fed; at += piece)
        s.part(f.data() + wire::kFrameHeaderSize + at, std::min(piece, fed - at));
    return judge(s, std::move(f));
}

// The sender's Box after a handshake at `level` (both ends, the same key) that the receiver
// accepted.
std::unique_ptr<sec::Box> sender_box(Handshake &h, Level level)
{
    LN_CHECK(h.run(level, level, key_of(3)) == wire::Reject::none);
    wire::Reply r;
    LN_CHECK(wire::decode_reply(h.reply, r));
    std::unique_ptr<sec::Box> box;
    LN_CHECK(check_tcp_reply(h.hello, r, h.reply, h.stream, sec::suite_for(level), box));
    LN_CHECK(box != nullptr);
    return box;
}

void test_tcp_session()
{
    {
        Handshake h;
        std::unique_ptr<sec::Box> box = sender_box(h, Level::encrypt);
        LN_CHECK(judge(h.session, frame(*box, 1, 10)) == TcpSession::Frame::intact);
        auto second = frame(*box, 2, 11);
        LN_CHECK(judge(h.session, second) == TcpSession::Frame::intact);
        // Frame 2 again as the third: its counter is implicit, so it does not open.
        LN_CHECK(judge(h.session, second) == TcpSession::Frame::rejected);
        // A reply whose tag is changed is not the receiver's.
        h.reply[wire::kReplySize - 1] ^= 1;
        wire::Reply r;
        LN_CHECK(wire::decode_reply(h.reply, r));
        LN_CHECK(
            !check_tcp_reply(h.hello, r, h.reply, h.stream, sec::suite_for(Level::encrypt), box));
    }
    {
        Handshake h; // tags computed while the payload arrives
        std::unique_ptr<sec::Box> box = sender_box(h, Level::authenticate);
        // In pieces or not, they judge as whole ones do.
        LN_CHECK(judge_streamed(h.session, frame(*box, 1, 7), 5) == TcpSession::Frame::intact);
        LN_CHECK(judge_streamed(h.session, frame(*box, 2, 8), 32) == TcpSession::Frame::intact);
        LN_CHECK(judge_streamed(h.session, frame(*box, 3, 9), 4, 12) == TcpSession::Frame::intact);
        LN_CHECK(judge(h.session, frame(*box, 4, 10)) == TcpSession::Frame::intact);
        auto bent = frame(*box, 5, 11);
        bent[wire::kFrameHeaderSize + 20] ^= 0x01;
        LN_CHECK(judge_streamed(h.session, bent, 8) == TcpSession::Frame::rejected);
    }
    {
        // Fed whole, the tag is the one of the bytes as they arrived: frame() does not read
        // the payload again (a receiver's slot is its own until published).
        Handshake h;
        std::unique_ptr<sec::Box> box = sender_box(h, Level::authenticate);
        auto f = frame(*box, 1, 12);
        uint8_t *payload = f.data() + wire::kFrameHeaderSize;
        h.session.begin(f.data());
        h.session.part(payload, 32);
        payload[0] ^= 0x01;
        LN_CHECK(judge(h.session, f) == TcpSession::Frame::intact);
    }
    {
        Handshake h; // a forged frame: the payload changed on the way
        std::unique_ptr<sec::Box> box = sender_box(h, Level::authenticate);
        auto f = frame(*box, 1, 10);
        f[wire::kFrameHeaderSize + 4] ^= 0x10;
        LN_CHECK(judge(h.session, f) == TcpSession::Frame::rejected);
    }
    {
        Handshake h; // the receiver has another key
        LN_CHECK(h.run(Level::authenticate, Level::authenticate, key_of(4)) == wire::Reject::key);
    }
    {
        Handshake h; // the levels differ
        LN_CHECK(h.run(Level::none, Level::authenticate, key_of(3)) == wire::Reject::security);
        Handshake g;
        LN_CHECK(g.run(Level::encrypt, Level::authenticate, key_of(3)) == wire::Reject::security);
    }
    {
        Handshake h; // none: no tags, the frame passes as it is
        LN_CHECK(h.run(Level::none, Level::none, key_of(4)) == wire::Reject::none);
        LN_CHECK_EQ(h.session.tag_size(), 0);
    }
}

} // namespace

int main()
{
    LN_CHECK(sodium_init() >= 0);
    LN_TEST_RUN(test_key_derivation);
    LN_TEST_RUN(test_suites);
    LN_TEST_RUN(test_replay_window);
    LN_TEST_RUN(test_tcp_session);
    LN_TEST_EXIT();
}
