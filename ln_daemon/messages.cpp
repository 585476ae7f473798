// The process messages' payloads filled from a Process (messages.hpp); the byte layout is the
// generated codec's (daemon_wire.hpp).
#include "messages.hpp"

namespace lnd {

wire::ProcessInfo process_info(const Process &p)
{
    wire::ProcessInfo info;
    info.name = p.name();
    info.pid = static_cast<uint32_t>(p.pid());
    info.state = static_cast<wire::State>(p.state());
    info.exit_kind = p.exit_kind();
    info.exit_value = p.exit_value();
    info.started = p.started();
    info.exited = p.exit_time();
    info.lines_kept = static_cast<uint32_t>(p.output().lines().size());
    info.lines_total = p.output().total();
    return info;
}

void encode_info(proto::Writer &w, const Process &p) { wire::encode(w, process_info(p)); }

void encode_lines(proto::Writer &w, const Process &p, uint32_t n, size_t budget)
{
    const auto &lines = p.output().lines();
    size_t count = 0, bytes = 4; // the count
    for (auto it = lines.rbegin(); it != lines.rend() && count < n; ++it) {
        size_t size = 1 + 8 + 4 + it->text.size(); // stream, time, text length, text
        if (bytes + size > budget)
            break;
        bytes += size;
        ++count;
    }
    wire::OutputLines reply;
    reply.lines.reserve(count);
    for (auto it = lines.end() - static_cast<std::ptrdiff_t>(count); it != lines.end(); ++it)
        reply.lines.push_back({it->stream, it->time, it->text});
    wire::encode(w, reply);
}

void encode_output_event(proto::Writer &w, const Process &p, const Line &line)
{
    wire::encode(w, wire::EvOutput{p.name(), line.stream, line.time, line.text});
}

void encode_exited_event(proto::Writer &w, const Process &p)
{
    wire::encode(w, wire::EvExited{p.name(), static_cast<uint32_t>(p.pid()), p.exit_kind(),
                                   p.exit_value(), p.exit_time()});
}

void encode_state_event(proto::Writer &w, const Process &p)
{
    wire::encode(w, wire::EvState{p.name(), static_cast<uint32_t>(p.pid()),
                                  static_cast<wire::State>(p.state())});
}

} // namespace lnd
