// Payloads of the ring and forwarding messages (docs/daemon.md, "Rings and forwarding"):
// decoding RING_* and STREAM_* requests, encoding the STREAM_LIST reply.  Decoders check
// structure only (lengths, flags, nothing left over); what the values mean is checked by
// whoever carries the request out.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "forward.hpp"
#include "protocol.hpp"

namespace lnd {

struct RingCreateRequest {
    std::string name; // shm name, "/ln.<sanitized instance>.<anything>"
    std::string topic;
    std::string md_name;
    uint64_t layout_hash = 0;
    uint64_t message_size = 0;
    uint32_t slots = 0;
    bool adopt = false; // take over an existing segment instead of failing
};

struct RingRetireRequest {
    std::string old_name;
    std::string successor;
    double timeout = 0;
};

struct RingReaderRequest {
    std::string name;
    uint32_t index = 0;
    int32_t pid = 0;
    uint32_t buffers = 0;
    bool reserve = false; // false: release
};

struct RingCountsRequest {
    std::string name;
    uint32_t publishers = 0;
    uint32_t subscribers = 0;
};

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

// Longest peer and last_error texts in STREAM_LIST; longer ones are cut.
constexpr size_t kMaxStatText = 256;

void encode_stream_list(proto::Writer &w, const fwd::Totals &totals,
                        const std::vector<fwd::StreamStats> &streams);

// "RING_CREATE" for Msg::ring_create and so on; nullptr for other types.
const char *net_msg_name(uint8_t type) noexcept;

} // namespace lnd
