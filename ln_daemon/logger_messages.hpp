// Payloads of the topic logging messages (docs/daemon.md, "Topic logging"): decoding the
// LOGGER_* requests, encoding the LOGGER_LIST reply and the head of LOGGER_DATA (its samples
// come straight out of the logger's buffer).  Decoders check structure only (lengths, flags,
// nothing left over); what the values mean is checked by the logger table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "protocol.hpp"

namespace lnd {

// LOGGER_TOPIC: create or update one topic of a logger.
struct LoggerTopicRequest {
    std::string logger;
    std::string topic;
    std::string ring; // shm name of the topic's ring on this host
    std::string md_name;
    uint64_t layout_hash = 0;
    uint64_t message_size = 0;
    uint32_t depth = 0;   // samples kept, >= 1
    uint32_t divisor = 0; // keep a sample iff seq % divisor == 0, >= 1
    double span_s = 0;    // 0: none; else drop samples older than newest - span
};

// LOGGER_REMOVE: one topic, or with topic "" the whole logger.
struct LoggerRemoveRequest {
    std::string logger;
    std::string topic;
};

struct LoggerEnableRequest {
    std::string logger;
    bool enable = false;
    bool clear = false;
};

struct LoggerFetchRequest {
    std::string logger;
    std::string topic;
    uint64_t after_seq = 0;
    uint32_t max_bytes = 0;
};

// Each is false if the payload is malformed (short, trailing bytes, a flag not 0 or 1, a
// string longer than proto::kMaxName).
bool decode_logger_topic(proto::Reader &r, LoggerTopicRequest &out);
bool decode_logger_remove(proto::Reader &r, LoggerRemoveRequest &out);
bool decode_logger_enable(proto::Reader &r, LoggerEnableRequest &out);
bool decode_logger_fetch(proto::Reader &r, LoggerFetchRequest &out);
// LOGGER_STATUS: just the logger ("" = every logger of the instance).
bool decode_logger_status(proto::Reader &r, std::string &logger);

// What a logger topic counted; see docs/daemon.md for each.
struct LoggerCounters {
    uint64_t received = 0; // samples the tap delivered while enabled
    uint64_t stored = 0;   // samples in the buffer now
    uint64_t missed = 0;   // sequence numbers the tap never delivered while enabled
    uint64_t skipped = 0;  // not kept because of the divisor
    uint64_t dropped = 0;  // evicted by depth or span (or by a restarted numbering)
};

// The fields of LOGGER_DATA before its samples.
struct LoggerDataHead {
    uint64_t message_size = 0;
    uint64_t layout_hash = 0;
    std::string md_name;
    bool enabled = false;
    LoggerCounters counters;
    uint64_t first_seq = 0; // of the buffer; 0 if it is empty
    uint64_t last_seq = 0;
    uint64_t start_seq = 0; // the ring's newest seq when the capture began reading it
};

// One entry of LOGGER_LIST.
struct LoggerTopicStatus {
    std::string logger;
    std::string topic;
    std::string ring;
    std::string md_name;
    bool enabled = false;
    uint32_t depth = 0;
    uint32_t divisor = 0;
    double span_s = 0;
    uint64_t message_size = 0;
    LoggerCounters counters;
    std::string last_error; // the current problem, "" if none (cut to kMaxLoggerErrorText)
};

// Longest last_error text in LOGGER_LIST; a longer one is cut.
constexpr size_t kMaxLoggerErrorText = 256;
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
