// Unit tests of the daemon's pure pieces: the payload Reader and the SPAWN decoder against
// truncated and trailing input, the key file checks, the HMAC derivations, the line
// splitter and the rotating output log (in a private temporary directory).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <ftw.h>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

#include "auth.hpp"
#include "daemon_test.hpp"
#include "messages.hpp"
#include "output.hpp"
#include "protocol.hpp"

using namespace lnd;

namespace {

std::string g_dir; // private temporary directory of this run

std::string write_file(const std::string &name, const std::string &text, mode_t mode)
{
    std::string path = g_dir + "/" + name;
    ::unlink(path.c_str());
    int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd >= 0) {
        ssize_t n = ::write(fd, text.data(), text.size());
        (void)n;
        ::fchmod(fd, mode);
        ::close(fd);
    }
    return path;
}

std::string read_file(const std::string &path)
{
    std::string text;
    int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0)
        return "(missing)";
    char buf[4096];
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;)
        text.append(buf, static_cast<size_t>(n));
    ::close(fd);
    return text;
}

std::string encoded_spawn()
{
    proto::Writer w;
    w.str("worker");
    w.u8(kSpawnPty);
    w.u32(2);
    w.str("sleep");
    w.str("10");
    w.u32(1);
    w.str("PATH=/bin");
    w.str("/tmp");
    w.u32(1);
    w.str("nofile");
    w.i64(64);
    w.i64(-1);
    w.str("SCHED_FIFO");
    w.i32(10);
    w.u32(2);
    w.u32(0);
    w.u32(1);
    w.u32(500);
    w.str("/tmp/log");
    w.u64(1000);
    w.u32(2);
    w.i32(2);
    w.f64(1.5);
    return w.buffer();
}

void test_reader_bounds()
{
    proto::Writer w;
    w.u32(7);
    w.str("abc");
    const std::string &b = w.buffer();
    proto::Reader r(b.data(), b.size());
    LN_CHECK_EQ(r.u32(), 7);
    CHECK_STR(r.str(), "abc");
    LN_CHECK(r.done());
    LN_CHECK_EQ(r.u8(), 0); // past the end: zero and failed
    LN_CHECK(!r.ok());

    proto::Reader limited(b.data() + 4, b.size() - 4);
    limited.str(2); // longer than the limit
    LN_CHECK(!limited.ok());

    proto::Writer huge;
    huge.u32(0xffffffffu); // a count no buffer could hold
    proto::Reader counted(huge.buffer().data(), huge.buffer().size());
    LN_CHECK_EQ(counted.count(4), 0);
    LN_CHECK(!counted.ok());
}

void test_decode_spawn()
{
    std::string b = encoded_spawn();
    proto::Reader r(b.data(), b.size());
    SpawnRequest req;
    LN_CHECK(decode_spawn(r, req));
    CHECK_STR(req.name, "worker");
    LN_CHECK(req.use_pty && !req.shell);
    LN_CHECK_EQ(req.argv.size(), 2);
    CHECK_STR(req.env.at(0), "PATH=/bin");
    LN_CHECK_EQ(req.rlimits.at(0).hard, -1);
    CHECK_STR(req.policy, "SCHED_FIFO");
    LN_CHECK_EQ(req.affinity.size(), 2);
    LN_CHECK_EQ(req.max_output_lines, 500);
    LN_CHECK_EQ(req.log_keep, 2);
    LN_CHECK(req.term_timeout == 1.5);

    // Every truncation is refused, and so are trailing bytes and unknown flags.
    int accepted = 0;
    for (size_t n = 0; n < b.size(); ++n) {
        proto::Reader t(b.data(), n);
        SpawnRequest partial;
        accepted += decode_spawn(t, partial);
    }
    LN_CHECK_EQ(accepted, 0);
    std::string longer = b + "x";
    proto::Reader t(longer.data(), longer.size());
    SpawnRequest extra;
    LN_CHECK(!decode_spawn(t, extra));
    std::string flags = b;
    flags[4 + 6] = static_cast<char>(0x80);
    proto::Reader f(flags.data(), flags.size());
    SpawnRequest bad;
    LN_CHECK(!decode_spawn(f, bad));
}

void test_key_file()
{
    const std::string hex = "00112233445566778899aabbccddeeff00112233445566778899AABBCCDDEEFF";
    Key key;
    std::string error;
    LN_CHECK(passed(load_key_file(write_file("good", hex + "\n", 0600), key), error));
    LN_CHECK_EQ(key.bytes[0], 0x00);
    LN_CHECK_EQ(key.bytes[31], 0xff);
    LN_CHECK(passed(load_key_file(write_file("nonl", hex, 0400), key), error));

    LN_CHECK(!passed(load_key_file(write_file("open", hex, 0644), key), error));
    LN_CHECK(error.find("is accessible by group or others (mode 0644)") != std::string::npos);
    LN_CHECK(!passed(load_key_file(write_file("group", hex, 0620), key), error));
    LN_CHECK(!passed(load_key_file(write_file("short", hex.substr(2), 0600), key), error));
    LN_CHECK(error.find("holds no valid key") != std::string::npos);
    LN_CHECK(!passed(load_key_file(write_file("nothex", "zz" + hex.substr(2), 0600), key), error));
    LN_CHECK(!passed(load_key_file(write_file("long", hex + hex, 0600), key), error));
    LN_CHECK(!passed(load_key_file(write_file("empty", "", 0600), key), error));
    LN_CHECK(!passed(load_key_file(g_dir + "/missing", key), error));
    LN_CHECK(error.find("cannot open key file") == 0);
    LN_CHECK(!passed(load_key_file(g_dir, key), error)); // a directory
    if (::geteuid() == 0) {                              // only root can give a file away
        std::string other = write_file("other", hex, 0600);
        LN_CHECK_EQ(::chown(other.c_str(), 12345, 12345), 0);
        LN_CHECK(!passed(load_key_file(other, key), error));
        LN_CHECK(error.find("is owned by uid 12345") != std::string::npos);
    }
}

void test_session_derivation()
{
    Key key;
    for (size_t i = 0; i < Key::kBytes; ++i)
        key.bytes[i] = static_cast<uint8_t>(i);
    uint8_t nd[32] = {1}, nc[32] = {2};
    Session a, b, c;
    derive_session(key, nd, nc, "inst", a);
    derive_session(key, nd, nc, "inst", b);
    derive_session(key, nd, nc, "other", c);
    LN_CHECK(tag_equal(a.client_proof, b.client_proof));
    LN_CHECK(!tag_equal(a.client_proof, c.client_proof)); // bound to the instance
    LN_CHECK(!tag_equal(a.client_proof, a.daemon_proof)); // the directions differ
    LN_CHECK(!tag_equal(a.to_daemon.bytes, a.to_client.bytes));
    nd[0] = 9;
    derive_session(key, nd, nc, "inst", c);
    LN_CHECK(!tag_equal(a.client_proof, c.client_proof)); // bound to the daemon's nonce

    Tag t0, t1, t0again;
    frame_tag(a.to_daemon, 0, "body", 4, t0);
    frame_tag(a.to_daemon, 1, "body", 4, t1);
    frame_tag(a.to_daemon, 0, "body", 4, t0again);
    LN_CHECK(tag_equal(t0, t0again));
    LN_CHECK(!tag_equal(t0, t1)); // a replayed frame has the wrong sequence number

    // Known answer, computed independently with Python's hmac module: the label, a NUL
    // byte, both nonces and the instance, keyed with the shared key.
    uint8_t n1[32], n2[32];
    std::memset(n1, 1, sizeof n1);
    std::memset(n2, 2, sizeof n2);
    derive_session(key, n1, n2, "inst", a);
    const char *expect = "99a0e60b395055d2d95cc4d2741524f22b1cc60297b05b0b95076bab9633ead9";
    char hex[65];
    for (int i = 0; i < 32; ++i)
        std::snprintf(hex + 2 * i, 3, "%02x", a.client_proof[i]);
    CHECK_STR(hex, expect);
}

void test_line_splitter()
{
    LineSplitter s;
    std::string got;
    auto emit = [&](std::string &&t) { got += "[" + t + "]"; };
    s.feed("a\nb", 3, 0, emit);
    CHECK_STR(got, "[a]");
    LN_CHECK(s.pending());
    s.feed("c\r\n\n", 4, 0, emit);
    CHECK_STR(got, "[a][bc][]");
    got.clear();
    std::string exact(kMaxLineBytes, 'y'); // exactly the limit, then its newline: one line
    exact += '\n';
    s.feed(exact.data(), exact.size(), 0, emit);
    LN_CHECK_EQ(got.size(), kMaxLineBytes + 2);
    got.clear();
    s.feed("tail", 4, 5.0, emit);
    LN_CHECK(s.flush_due() == 5.0 + kPartialFlushDelay);
    s.flush(emit);
    CHECK_STR(got, "[tail]");
    LN_CHECK(!s.pending());
}

void test_line_buffer_is_bounded_in_bytes()
{
    // A process writing long lines must not make the daemon hold max_output_lines of them
    // (up to 1000000 x 16 KiB): the text kept is bounded in bytes as well, oldest dropped.
    LineBuffer buf(kMaxOutputLines);
    std::string text(kMaxLineBytes, 'z');
    size_t n = kMaxKeptBytes / kMaxLineBytes + 10;
    for (size_t i = 0; i < n; ++i)
        buf.add({double(i), proto::Stream::out, text});
    LN_CHECK_EQ(buf.total(), n);
    LN_CHECK_EQ(buf.lines().size(), kMaxKeptBytes / kMaxLineBytes);
    LN_CHECK(buf.lines().back().time == double(n - 1));
    LN_CHECK(buf.lines().front().time == double(n - kMaxKeptBytes / kMaxLineBytes));
    buf.add({0, proto::Stream::out, std::string()}); // empty lines count too, and fit
    LN_CHECK_EQ(buf.lines().size(), kMaxKeptBytes / kMaxLineBytes + 1);

    LineBuffer few(3); // the line count still applies
    for (int i = 0; i < 5; ++i)
        few.add({double(i), proto::Stream::out, "x"});
    LN_CHECK_EQ(few.lines().size(), 3);
}

void test_rotating_log()
{
    std::string path = g_dir + "/out.log";
    RotatingLog log;
    std::string error;
    LN_CHECK(passed(log.open(path, 10, 2), error));
    for (const char *line : {"11111", "22222", "33333", "44444", "55555"})
        log.write_line(line); // 6 bytes each: one line per file
    CHECK_STR(read_file(path), "55555\n");
    CHECK_STR(read_file(path + ".1"), "44444\n");
    CHECK_STR(read_file(path + ".2"), "33333\n");
    CHECK_STR(read_file(path + ".3"), "(missing)");

    std::string single = g_dir + "/single.log";
    RotatingLog keep0;
    LN_CHECK(passed(keep0.open(single, 8, 0), error));
    keep0.write_line("abc");
    keep0.write_line("def"); // 4 + 4 = 8 fits
    keep0.write_line("ghi"); // would be 12: truncated and restarted
    CHECK_STR(read_file(single), "ghi\n");
    CHECK_STR(read_file(single + ".1"), "(missing)");

    RotatingLog bad;
    LN_CHECK(!passed(bad.open(g_dir + "/no/such/dir/log", 0, 0), error));
    LN_CHECK(error.find("cannot open output log") == 0);
}

int remove_entry(const char *path, const struct stat *, int, struct FTW *)
{
    return ::remove(path);
}

} // namespace

int main()
{
    crypto_init();
    char tmpl[] = "/tmp/ln_daemon_test.XXXXXX";
    if (!::mkdtemp(tmpl))
        return 1;
    g_dir = tmpl;
    LN_TEST_RUN(test_reader_bounds);
    LN_TEST_RUN(test_decode_spawn);
    LN_TEST_RUN(test_key_file);
    LN_TEST_RUN(test_session_derivation);
    LN_TEST_RUN(test_line_splitter);
    LN_TEST_RUN(test_line_buffer_is_bounded_in_bytes);
    LN_TEST_RUN(test_rotating_log);
    ::nftw(g_dir.c_str(), remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    LN_TEST_EXIT();
}
