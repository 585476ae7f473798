// Message payload codecs (messages.hpp).  Decoding bounds every count by the bytes left, so
// a hostile length cannot make the daemon allocate more than the frame it already holds.
#include "messages.hpp"

namespace lnd {

bool decode_spawn(proto::Reader &r, SpawnRequest &out)
{
    out.name = r.str(proto::kMaxName);
    uint8_t flags = r.u8();
    if (flags & ~(kSpawnShell | kSpawnPty))
        return false;
    out.shell = flags & kSpawnShell;
    out.use_pty = flags & kSpawnPty;
    for (uint32_t i = 0, n = r.count(4); i < n && r.ok(); ++i)
        out.argv.push_back(r.str());
    for (uint32_t i = 0, n = r.count(4); i < n && r.ok(); ++i)
        out.env.push_back(r.str());
    out.cwd = r.str();
    for (uint32_t i = 0, n = r.count(20); i < n && r.ok(); ++i) {
        RlimitRequest lim;
        lim.name = r.str(64);
        lim.soft = r.i64();
        lim.hard = r.i64();
        out.rlimits.push_back(std::move(lim));
    }
    out.policy = r.str(64);
    out.priority = r.i32();
    for (uint32_t i = 0, n = r.count(4); i < n && r.ok(); ++i)
        out.affinity.push_back(r.u32());
    out.max_output_lines = r.u32();
    out.log_path = r.str();
    out.log_limit = r.u64();
    out.log_keep = r.u32();
    out.term_signal = r.i32();
    out.term_timeout = r.f64();
    return r.done();
}

void encode_info(proto::Writer &w, const Process &p)
{
    w.str(p.name());
    w.u32(static_cast<uint32_t>(p.pid()));
    w.u8(static_cast<uint8_t>(p.state()));
    w.u8(static_cast<uint8_t>(p.exit_kind()));
    w.i32(p.exit_value());
    w.f64(p.started());
    w.f64(p.exit_time());
    w.u32(static_cast<uint32_t>(p.output().lines().size()));
    w.u64(p.output().total());
}

void encode_lines(proto::Writer &w, const Process &p, uint32_t n, size_t budget)
{
    const auto &lines = p.output().lines();
    size_t count = 0, bytes = 4;
    for (auto it = lines.rbegin(); it != lines.rend() && count < n; ++it) {
        size_t size = 1 + 8 + 4 + it->text.size();
        if (bytes + size > budget)
            break;
        bytes += size;
        ++count;
    }
    w.u32(static_cast<uint32_t>(count));
    for (auto it = lines.end() - static_cast<std::ptrdiff_t>(count); it != lines.end(); ++it) {
        w.u8(static_cast<uint8_t>(it->stream));
        w.f64(it->time);
        w.str(it->text);
    }
}

void encode_output_event(proto::Writer &w, const Process &p, const Line &line)
{
    w.str(p.name());
    w.u8(static_cast<uint8_t>(line.stream));
    w.f64(line.time);
    w.str(line.text);
}

void encode_exited_event(proto::Writer &w, const Process &p)
{
    w.str(p.name());
    w.u32(static_cast<uint32_t>(p.pid()));
    w.u8(static_cast<uint8_t>(p.exit_kind()));
    w.i32(p.exit_value());
    w.f64(p.exit_time());
}

void encode_state_event(proto::Writer &w, const Process &p)
{
    w.str(p.name());
    w.u32(static_cast<uint32_t>(p.pid()));
    w.u8(static_cast<uint8_t>(p.state()));
}

} // namespace lnd
