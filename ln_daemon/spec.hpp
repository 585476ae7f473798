// A SPAWN request as it arrives (SpawnRequest) and its checking into what the OS layer and
// the process record need; every refusal is a sentence naming the offending field.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "os.hpp"
#include "outcome.hpp"
#include "protocol.hpp"

namespace lnd {

// A SPAWN request as it arrives: the generated struct of daemon.schema's SPAWN message (its
// fields and defaults are the schema's).
using RlimitRequest = wire::RlimitRequest;
using SpawnRequest = wire::Spawn;

// What the process record keeps besides the launch itself.
struct ProcessConfig {
    std::string instance;
    std::string name;
    uint32_t max_output_lines = 1000;
    std::string log_path;
    uint64_t log_limit = 0;
    uint32_t log_keep = 0;
    int term_signal = 15;
    double term_timeout = 5.0;
};

constexpr uint32_t kMaxOutputLines = 1000000;
constexpr uint32_t kMaxLogKeep = 1000;

// True if `s` is a valid instance or process name: 1..255 bytes, no control characters.
bool valid_name(const std::string &s) noexcept;

// Appends NAME=value to `env` unless it has an entry for NAME already.
void env_default(std::vector<std::string> &env, const std::string &name, const std::string &value);

// Checks `req` into `launch` and `config`; refused with error invalid_spec and a sentence.
Outcome check_spawn(const SpawnRequest &req, LaunchSpec &launch, ProcessConfig &config);

// The sentence for a failed child setup, e.g. "command not found: foo".
std::string describe_failure(const LaunchSpec &spec, int32_t stage, int32_t index, int32_t err);

// "SCHED_FIFO" for SCHED_FIFO and so on.
const char *policy_name(int policy) noexcept;

} // namespace lnd
