// Payloads of the ring and forwarding messages (docs/daemon.md, "Rings and forwarding"):
// the RING_* and STREAM_* requests through the generated codec (daemon_wire.hpp), the
// forwarder's specs and stats converted from and to its structs.  Decoders check structure
// only (lengths, flags, nothing left over); what the values mean is checked by whoever
// carries the request out.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "forward.hpp"
#include "protocol.hpp"

namespace lnd {

// The requests as they arrive: the generated structs of daemon.schema.
using RingCreateRequest = wire::RingCreate;
using RingRetireRequest = wire::RingRetire;
using RingReaderRequest = wire::RingReader;
using RingCountsRequest = wire::RingCounts;

// Each is false if the payload is malformed (short, trailing bytes, a flag not 0 or 1, a
// name longer than proto::kMaxName).
bool decode_ring_create(proto::Reader &r, RingCreateRequest &out);
bool decode_ring_retire(proto::Reader &r, RingRetireRequest &out);
bool decode_ring_reader(proto::Reader &r, RingReaderRequest &out);
bool decode_ring_counts(proto::Reader &r, RingCountsRequest &out);
// RING_REMOVE and RING_SEQ: just the name.
bool decode_ring_name(proto::Reader &r, std::string &name);
bool decode_stream_send(proto::Reader &r, fwd::SendSpec &out);
bool decode_stream_recv(proto::Reader &r, fwd::RecvSpec &out);
bool decode_stream_token(proto::Reader &r, uint64_t &token);

// Longest ring, peer and last_error texts in STREAM_LIST; longer ones are cut.
constexpr size_t kMaxStatText = wire::kMaxStatText;

void encode_stream_list(proto::Writer &w, const fwd::Totals &totals,
                        const std::vector<fwd::StreamStats> &streams);

// "RING_CREATE" for Msg::ring_create and so on; nullptr for types of other families.
const char *net_msg_name(uint8_t type) noexcept;

} // namespace lnd
