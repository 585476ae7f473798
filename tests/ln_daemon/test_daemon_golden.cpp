// The daemon's generated codec (daemon_wire.hpp, from daemon.schema) against the golden
// vectors of tests/wire/daemon_golden.txt, which the manager's Python codec must match too
// (tests/python/wire/test_daemon_golden.py): each vector's values encode to exactly its
// bytes, the bytes decode and encode back to the same, every shorter payload is refused and
// so is one with a byte left over; and every message type has a vector.
#include <cstdio>
#include <set>
#include <string>

#include "daemon_test.hpp"
#include "protocol.hpp"

#include "daemon_golden_cases.hpp"

using namespace lnd;

namespace {

std::string from_hex(const std::string &hex)
{
    std::string out;
    for (size_t i = 0; i + 1 < hex.size(); i += 2)
        out.push_back(static_cast<char>(std::stoi(hex.substr(i, 2), nullptr, 16)));
    return out;
}

void report(const char *name, int line, const char *what)
{
    std::fprintf(stderr, "    %s (tests/wire/daemon_golden.txt:%d): %s\n", name, line, what);
}

struct Golden {
    std::set<std::string> seen;

    template <typename T>
    void check(const T &value, const char *name, int line, const std::string &hex, size_t head)
    {
        seen.insert(name);
        CHECK_STR(wire::name(T::kType), name);
        const std::string payload = from_hex(hex);
        proto::Writer w;
        wire::encode(w, value);
        if (w.buffer() != payload)
            report(name, line, "the values encode to other bytes");
        LN_CHECK(w.buffer() == payload);

        T decoded;
        proto::Reader r(payload.data(), payload.size());
        bool ok = wire::decode(r, decoded);
        if (!ok)
            report(name, line, "the bytes do not decode");
        LN_CHECK(ok);
        proto::Writer again;
        wire::encode(again, decoded);
        if (again.buffer() != payload)
            report(name, line, "the decoded values encode to other bytes");
        LN_CHECK(again.buffer() == payload);

        for (size_t cut = 0; cut < head; ++cut) {
            T partial;
            proto::Reader short_r(payload.data(), cut);
            if (wire::decode(short_r, partial)) {
                report(name, line, "a shorter payload decodes");
                LN_CHECK(false);
                break;
            }
        }
        if (head == payload.size()) {
            std::string longer = payload + '\0';
            T extra;
            proto::Reader long_r(longer.data(), longer.size());
            if (wire::decode(long_r, extra))
                report(name, line, "a byte left over is accepted");
            LN_CHECK(!wire::decode(long_r, extra));
        }
    }
};

void test_golden_vectors()
{
    Golden g;
    golden_cases(g);
    LN_CHECK(g.seen.size() > 40);
    for (unsigned type = 0; type < 256; ++type) {
        const char *name = wire::name(static_cast<wire::Msg>(type));
        if (name && !g.seen.count(name)) {
            std::fprintf(stderr, "    no golden vector of %s\n", name);
            LN_CHECK(g.seen.count(name));
        }
    }
}

void test_spawn_defaults_are_the_schema_s()
{
    wire::Spawn req; // what a SPAWN without those fields would mean
    LN_CHECK(req.use_pty);
    LN_CHECK(!req.shell);
    CHECK_STR(req.policy, "SCHED_OTHER");
    LN_CHECK_EQ(req.max_output_lines, 1000);
    LN_CHECK_EQ(req.term_signal, 15);
    LN_CHECK(req.term_timeout == 5.0);
}

void test_refusals()
{
    proto::Writer w;
    wire::encode(
        w, wire::StreamRecv{1, "/ln.i.1", 2, 3, wire::Transport::tcp, wire::Security::encrypt});
    std::string bad = w.buffer();
    bad.back() = 3; // no Security
    wire::StreamRecv recv;
    proto::Reader r(bad.data(), bad.size());
    LN_CHECK(!wire::decode(r, recv));

    proto::Writer s;
    wire::encode(s, wire::Signal{"p", 9, true});
    std::string two = s.buffer();
    two.back() = 2; // a bool of 2
    wire::Signal sig;
    proto::Reader r2(two.data(), two.size());
    LN_CHECK(!wire::decode(r2, sig));

    proto::Writer l;
    l.u32(1000); // processes: more than the payload can hold
    l.raw(std::string(40, '\0').data(), 40);
    wire::ProcessList list;
    proto::Reader r3(l.buffer().data(), l.buffer().size());
    LN_CHECK(!wire::decode(r3, list));
    LN_CHECK(list.processes.capacity() < 1000);
}

} // namespace

int main()
{
    LN_TEST_RUN(test_golden_vectors);
    LN_TEST_RUN(test_spawn_defaults_are_the_schema_s);
    LN_TEST_RUN(test_refusals);
    LN_TEST_EXIT();
}
