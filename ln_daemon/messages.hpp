// Payloads of the protocol's messages (docs/daemon.md lists them field by field): decoding
// SPAWN, encoding process records, output lines and events.
#pragma once

#include <cstdint>

#include "process.hpp"
#include "protocol.hpp"
#include "spec.hpp"

namespace lnd {

// SPAWN flags
constexpr uint8_t kSpawnShell = 1;
constexpr uint8_t kSpawnPty = 2;

// False if the payload is malformed (short, trailing bytes, unknown flags).
bool decode_spawn(proto::Reader &r, SpawnRequest &out);

void encode_info(proto::Writer &w, const Process &p);
// The last `n` lines of `p`, oldest first, at most `budget` bytes of payload.
void encode_lines(proto::Writer &w, const Process &p, uint32_t n, size_t budget);
void encode_output_event(proto::Writer &w, const Process &p, const Line &line);
void encode_exited_event(proto::Writer &w, const Process &p);
void encode_state_event(proto::Writer &w, const Process &p);

} // namespace lnd
