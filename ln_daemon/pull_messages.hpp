// Payloads of the pull topic messages (docs/daemon.md, "Pull topics"): decoding the PULL_*
// requests and encoding the PULL_LIST reply.  Decoders check structure only (lengths,
// nothing left over); what the values mean is checked by the pull table (pulls.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "protocol.hpp"

namespace lnd {

constexpr size_t kMaxPullName = 1024; // bytes of the NDN URI in PULL_TOPIC
constexpr size_t kMaxPullKey = 255;   // bytes of the HMAC key in PULL_TOPIC

// PULL_TOPIC: serve one topic of the instance (create, update or move it).
struct PullTopicRequest {
    std::string topic;
    std::string ring; // shm name of the topic's ring on this host
    std::string md_name;
    uint64_t layout_hash = 0;
    uint64_t message_size = 0;
    std::string address; // bind address, "" = 0.0.0.0
    uint16_t port = 0;
    std::string name; // NDN URI the topic is served under, e.g. "/ln/robot/arm.state"
    uint32_t history = 0;
    uint32_t freshness_ms = 0;
    uint8_t signature = 0; // 0 DigestSha256, 4 HMAC-SHA256
    std::string key;       // HMAC key bytes ("" with DigestSha256)
};

// Each is false if the payload is malformed (short, trailing bytes, a string longer than
// proto::kMaxName, or kMaxPullName / kMaxPullKey for the name and the key).
bool decode_pull_topic(proto::Reader &r, PullTopicRequest &out);
// PULL_REMOVE and PULL_STATUS: just the topic ("" = every pull topic of the instance).
bool decode_pull_topic_name(proto::Reader &r, std::string &topic);
// What the Python client sends: the inverse of decode_pull_topic (tests and the fuzz target).
void encode_pull_topic(proto::Writer &w, const PullTopicRequest &req);

// What a UDP port counted (PULL_LIST); see docs/daemon.md for each.
struct PullPortCounters {
    uint64_t packets = 0; // datagrams received
    uint64_t bad = 0;     // did not decode (or did not fit the receive buffer)
    uint64_t unknown = 0; // Interests for a name no topic serves
    uint64_t other = 0;   // Data, LP Nacks: not an Interest
};

struct PullPortStatus {
    std::string address;
    uint16_t port = 0; // the bound port
    PullPortCounters counters;
    std::string last_error;
};

// What a pull topic counted; see docs/daemon.md for each.
struct PullTopicCounters {
    uint64_t interests = 0;  // Interests for the topic (sync and seq, duplicates included)
    uint64_t syncs = 0;      // of them, sync Interests
    uint64_t data = 0;       // Data sent (samples and sync replies)
    uint64_t nacks = 0;      // application NACKs sent
    uint64_t parked = 0;     // Interests parked for a seq not published yet
    uint64_t expired = 0;    // parked Interests that expired unanswered (dropped silently)
    uint64_t duplicates = 0; // Interests dropped: same name and nonce seen recently
    uint64_t overflow = 0;   // parked table full: answered with a NACK instead
};

struct PullTopicStatus {
    std::string topic;
    std::string name;
    std::string ring;
    std::string address;
    uint16_t port = 0; // the bound port
    uint32_t history = 0;
    uint64_t latest_seq = 0;
    PullTopicCounters counters;
    std::string last_error;
};

// Longest last_error text in PULL_LIST; a longer one is cut.
constexpr size_t kMaxPullErrorText = 256;

void encode_pull_list(proto::Writer &w, const std::vector<PullPortStatus> &ports,
                      const std::vector<PullTopicStatus> &topics);
// The inverse, for tests; false if malformed.
bool decode_pull_list(proto::Reader &r, std::vector<PullPortStatus> &ports,
                      std::vector<PullTopicStatus> &topics);

// "PULL_TOPIC" for Msg::pull_topic and so on; nullptr for other types.
const char *pull_msg_name(uint8_t type) noexcept;

} // namespace lnd
