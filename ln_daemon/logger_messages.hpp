// Payloads of the topic logging messages (docs/daemon.md, "Topic logging") through the
// generated codec (daemon_wire.hpp): the LOGGER_* requests, the LOGGER_LIST reply and the
// head of LOGGER_DATA (its samples come straight out of the logger's buffer).  Decoders
// check structure only (lengths, flags, nothing left over); what the values mean is checked
// by the logger table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "protocol.hpp"

namespace lnd {

// The requests as they arrive: the generated structs of daemon.schema.
using LoggerTopicRequest = wire::LoggerTopic;   // create or update one topic of a logger
using LoggerRemoveRequest = wire::LoggerRemove; // one topic, or with topic "" the logger
using LoggerEnableRequest = wire::LoggerEnable;
using LoggerFetchRequest = wire::LoggerFetch;

// Each is false if the payload is malformed (short, trailing bytes, a flag not 0 or 1, a
// string longer than proto::kMaxName).
bool decode_logger_topic(proto::Reader &r, LoggerTopicRequest &out);
bool decode_logger_remove(proto::Reader &r, LoggerRemoveRequest &out);
bool decode_logger_enable(proto::Reader &r, LoggerEnableRequest &out);
bool decode_logger_fetch(proto::Reader &r, LoggerFetchRequest &out);
// LOGGER_STATUS: just the logger ("" = every logger of the instance).
bool decode_logger_status(proto::Reader &r, std::string &logger);

// What a logger topic counted (see docs/daemon.md for each), the fields of LOGGER_DATA
// before its samples (its `samples` stay empty: the buffer appends them) and one entry of
// LOGGER_LIST: the generated structs.
using LoggerCounters = wire::LoggerCounters;
using LoggerDataHead = wire::LoggerData;
using LoggerTopicStatus = wire::LoggerTopicStatus;

// Longest last_error text in LOGGER_LIST; a longer one is cut.
constexpr size_t kMaxLoggerErrorText = wire::kMaxStatText;
// Bytes of LOGGER_DATA before its samples, at most (the md name at its longest).
constexpr size_t kLoggerDataHeadBytes = 8 + 8 + 4 + proto::kMaxName + 1 + 8 * 8 + 4;
// Payload bytes a LOGGER_DATA reply may have: the frame minus its header and tag.
constexpr size_t kMaxReplyPayload = proto::kMaxFrame - proto::kHeaderBytes - proto::kTagBytes;
// Bytes one sample takes in LOGGER_DATA: seq, timestamp, the message.
constexpr uint64_t logger_sample_wire_bytes(uint64_t message_size) { return 16 + message_size; }
// The largest message a logger takes: one sample has to fit a LOGGER_DATA reply.
constexpr uint64_t kMaxLoggedMessage = kMaxReplyPayload - kLoggerDataHeadBytes - 16;

// The head of LOGGER_DATA; the caller appends u32 count and the samples.
void encode_logger_data_head(proto::Writer &w, const LoggerDataHead &head);
void encode_logger_list(proto::Writer &w, uint64_t memory_limit, uint64_t memory_used,
                        const std::vector<LoggerTopicStatus> &topics);

// "LOGGER_TOPIC" for Msg::logger_topic and so on; nullptr for other types.
const char *logger_msg_name(uint8_t type) noexcept;

} // namespace lnd
