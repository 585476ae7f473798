// The daemon's poll loop and its TCP side: accepting connections, the authentication
// handshake, framing with per-frame tags, dispatching each request to the feature that owns
// its message type (processes, network, loggers, pull topics: feature.hpp), and turning the
// Supervisor's news into replies and events.  A connection that misbehaves is closed with one
// log line; nothing it sends can affect another connection or a process.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <functional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "auth.hpp"
#include "fd.hpp"
#include "feature.hpp"
#include "process.hpp"
#include "processes.hpp"
#include "protocol.hpp"
#include "resources.hpp"

namespace lnd {

constexpr size_t kMaxConnections = 256;
constexpr size_t kMaxQueuedBytes = 64u << 20; // a connection that falls further behind is closed
constexpr double kHandshakeTimeout = 10.0;
constexpr double kLingerTimeout = 2.0; // after a final error, for the peer to read it
constexpr double kAcceptPause = 0.1;   // after accept() ran out of descriptors

struct Connection;

class Server final : public Sink {
public:
    // `listener` is a bound, listening, non-blocking socket; `signals` a signalfd for
    // SIGCHLD, SIGTERM, SIGINT and SIGHUP.  `log_path` is reopened on SIGHUP.  `host_id`
    // is the LN_HOST_ID of spawned processes.  The server runs the process requests itself;
    // `features` take the others (in this order at shutdown) and must outlive the server.
    // `resource_period` is the default period of RESOURCES (0: resource samples are refused).
    Server(Os &os, const Key &key, UniqueFd listener, UniqueFd signals, std::string log_path,
           std::string host_id, std::vector<Feature *> features,
           double resource_period = res::kDefaultPeriod);
    ~Server() override;
    // Runs until SIGTERM/SIGINT has stopped every process, then shuts the features down;
    // returns the exit status.
    int run();
    // On SIGHUP, also read the key file at `path` again; a key that changed is used for new
    // manager connections from then on and handed to `apply` (the forwarder's set_key).
    void reload_key_on_hangup(std::string path, std::function<void(const Key &)> apply);

    void spawn_result(const Process &p, const Outcome &result) override;
    void line(const Process &p, const Line &line) override;
    void state_changed(const Process &p) override;
    void exited(const Process &p) override;

private:
    void accept_all();
    // Makes room for a new connection at the limit; false if every connection is authenticated.
    bool evict_unauthenticated();
    void read_signals();
    void on_readable(Connection &c);
    void parse_frames(Connection &c);
    void handle_hello(Connection &c, uint8_t type, proto::Reader &r);
    void handle_request(Connection &c, uint8_t type, uint32_t req, proto::Reader &r);
    // The feature that takes `type`, or nullptr.
    Feature *owner(uint8_t type) const noexcept;
    void flush(Connection &c);
    void send(Connection &c, proto::Msg type, uint32_t req, const std::string &payload);
    void send_error(Connection &c, uint32_t req, proto::Err code, const std::string &text);
    // Sends a last error, then closes the connection once the peer had a chance to read it.
    void refuse(Connection &c, uint32_t req, proto::Err code, const std::string &text);
    void drop(Connection &c, const char *why);
    void broadcast(const std::string &instance, proto::Msg type, const std::string &payload);
    void begin_shutdown();
    // RESOURCES: this connection's period of EV_RESOURCES.
    void resources_request(Connection &c, uint32_t req, proto::Reader &r);
    // The next EV_RESOURCES due (monotonic; +inf if none); sends those due at `now`.
    double resources_due() const noexcept;
    void send_resources(double now);

    void reload_key();

    Os &os_;
    Key key_;
    std::string key_path_; // "" : SIGHUP leaves the key alone
    std::function<void(const Key &)> key_apply_;
    UniqueFd listener_;
    UniqueFd signals_;
    std::string log_path_;
    Processes processes_;
    Supervisor &supervisor_;          // processes_'
    std::vector<Feature *> features_; // processes_ first
    std::map<uint64_t, std::unique_ptr<Connection>> conns_;
    uint64_t next_conn_ = 1;
    uint64_t next_request_ = 1;
    // Deferred answers: request id -> connection, request number
    std::unordered_map<uint64_t, std::pair<uint64_t, uint32_t>> pending_;
    int shutdown_signals_ = 0;
    double accept_paused_until_ = 0; // monotonic
    double resource_period_;
    res::Sampler sampler_;
    wire::EvResources sample_;   // reused: its vectors keep their capacity
    bool sample_failed_ = false; // logged once until a sample succeeds again
};

} // namespace lnd
