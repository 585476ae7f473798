// Payloads of the pull topic messages (docs/daemon.md, "Pull topics") through the generated
// codec (daemon_wire.hpp): the PULL_* requests and the PULL_LIST reply.  Decoders check
// structure only (lengths, nothing left over); what the values mean is checked by the pull
// table (pulls.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "protocol.hpp"

namespace lnd {

constexpr size_t kMaxPullName = wire::kMaxPullName; // bytes of the NDN URI in PULL_TOPIC
constexpr size_t kMaxPullKey = wire::kMaxPullKey;   // bytes of the HMAC key in PULL_TOPIC

// PULL_TOPIC: serve one topic of the instance (create, update or move it); the generated
// struct of daemon.schema.
using PullTopicRequest = wire::PullTopic;

// Each is false if the payload is malformed (short, trailing bytes, a string longer than
// proto::kMaxName, or kMaxPullName / kMaxPullKey for the name and the key).
bool decode_pull_topic(proto::Reader &r, PullTopicRequest &out);
// PULL_REMOVE and PULL_STATUS: just the topic ("" = every pull topic of the instance).
bool decode_pull_topic_name(proto::Reader &r, std::string &topic);
// What the Python client sends: the inverse of decode_pull_topic (tests and the fuzz target).
void encode_pull_topic(proto::Writer &w, const PullTopicRequest &req);

// What a UDP port and a pull topic counted and show in PULL_LIST (see docs/daemon.md for
// each): the generated structs.
using PullPortCounters = wire::PullPortCounters;
using PullPortStatus = wire::PullPortStatus;
using PullTopicCounters = wire::PullTopicCounters;
using PullTopicStatus = wire::PullTopicStatus;

// Longest last_error text in PULL_LIST; a longer one is cut.
constexpr size_t kMaxPullErrorText = wire::kMaxStatText;

void encode_pull_list(proto::Writer &w, const std::vector<PullPortStatus> &ports,
                      const std::vector<PullTopicStatus> &topics);
// The inverse, for tests; false if malformed.
bool decode_pull_list(proto::Reader &r, std::vector<PullPortStatus> &ports,
                      std::vector<PullTopicStatus> &topics);

// "PULL_TOPIC" for Msg::pull_topic and so on; nullptr for other types.
const char *pull_msg_name(uint8_t type) noexcept;

} // namespace lnd
