// The daemon's network commands (docs/daemon.md, "Rings and forwarding"): NET_INFO, the
// RING_* requests that administer topic rings on this host for a remote manager, and the
// STREAM_* requests that make the Forwarder send or receive topics.  Rings and streams
// belong to an instance and outlive its connections; a later manager of the instance adopts
// its rings again or purges them.  Runs in the poll loop; the Forwarder's own threads move
// the data.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>

#include "feature.hpp"
#include "forward.hpp"
#include "outcome.hpp"
#include "protocol.hpp"
#include "rings.hpp"

namespace lnd {

constexpr size_t kMaxStreams = 4096; // per daemon, all instances (STREAM_LIST fits one frame)

class NetCommands final : public Feature {
public:
    // `host_id` is what NET_INFO reports and spawned processes get as LN_HOST_ID;
    // `data_port` the port NET_INFO advertises.  `forwarder` must outlive this.
    NetCommands(std::string host_id, uint16_t data_port, fwd::Forwarder &forwarder);

    bool handles(uint8_t type) const noexcept override;
    Outcome handle(const Request &req) override;

    const std::string &host_id() const noexcept { return host_id_; }

private:
    Outcome rings(const std::string &instance, uint8_t type, proto::Reader &r);
    Outcome streams(const std::string &instance, uint8_t type, proto::Reader &r);
    // Whether `instance` may add or replace stream `token` on `ring`.
    Outcome admit(const std::string &instance, uint64_t token, const std::string &ring) const;
    // The reply to STREAM_SEND/RECV given the Forwarder's verdict.
    Outcome added(const std::string &instance, uint64_t token, const std::string &ring,
                  const char *what, Outcome verdict);
    Outcome purge(const std::string &instance);

    std::string host_id_;
    uint16_t data_port_;
    fwd::Forwarder &forwarder_;
    RingTable rings_;
    std::unordered_map<uint64_t, std::string> streams_; // token -> instance
};

} // namespace lnd
