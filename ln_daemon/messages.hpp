// Payloads of the process messages (docs/daemon.md lists them field by field): SPAWN is
// decoded by the generated codec (daemon_wire.hpp); here the process records, output lines
// and events are filled from a Process and encoded.
#pragma once

#include <cstdint>

#include "process.hpp"
#include "protocol.hpp"
#include "spec.hpp"

namespace lnd {

// SPAWN flags (daemon.schema, SpawnFlags)
constexpr uint8_t kSpawnShell = wire::SpawnFlags::shell;
constexpr uint8_t kSpawnPty = wire::SpawnFlags::use_pty;

// False if the payload is malformed (short, trailing bytes, unknown flags).
inline bool decode_spawn(proto::Reader &r, SpawnRequest &out) { return wire::decode(r, out); }

wire::ProcessInfo process_info(const Process &p);
void encode_info(proto::Writer &w, const Process &p);
// The last `n` lines of `p`, oldest first, at most `budget` bytes of payload.
void encode_lines(proto::Writer &w, const Process &p, uint32_t n, size_t budget);
void encode_output_event(proto::Writer &w, const Process &p, const Line &line);
void encode_exited_event(proto::Writer &w, const Process &p);
void encode_state_event(proto::Writer &w, const Process &p);

} // namespace lnd
