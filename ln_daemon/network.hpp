// The daemon's network commands (docs/daemon.md, "Rings and forwarding"): NET_INFO, the
// RING_* requests that administer topic rings on this host for a remote manager, and the
// STREAM_* requests that make the Forwarder send or receive topics.  Rings and streams
// belong to an instance and outlive its connections; a later manager of the instance adopts
// its rings again or purges them.  Runs in the poll loop; the Forwarder's own threads move
// the data.
#pragma once

#include <cstdint>
#include <exception>
#include <new>
#include <string>
#include <unordered_map>
#include <utility>

#include "forward.hpp"
#include "log.hpp"
#include "protocol.hpp"
#include "rings.hpp"

namespace lnd {

constexpr size_t kMaxStreams = 4096; // per daemon, all instances (STREAM_LIST fits one frame)

// What the server sends for one request.
struct NetOutcome {
    enum class Kind { reply, error, malformed };
    Kind kind = Kind::reply;
    proto::Msg type = proto::Msg::ok; // reply
    std::string payload;              // reply
    proto::Err code = proto::Err::bad_request; // error
    std::string text;                          // error
};

// Building outcomes (network.cpp, loggers.cpp).
namespace outcome {
inline NetOutcome ok() { return {}; }
inline NetOutcome reply(proto::Msg type, std::string payload)
{
    NetOutcome o;
    o.type = type;
    o.payload = std::move(payload);
    return o;
}
inline NetOutcome error(proto::Err code, std::string text)
{
    NetOutcome o;
    o.kind = NetOutcome::Kind::error;
    o.code = code;
    o.text = std::move(text);
    return o;
}
inline NetOutcome malformed()
{
    NetOutcome o;
    o.kind = NetOutcome::Kind::malformed;
    return o;
}
// The daemon's one convention for a request handler's exceptions: run `dispatch`; bad_alloc
// propagates (the connection is dropped, Server::on_readable); any other exception (a thread
// or an eventfd that could not be made) is logged for `instance` and answered as error `code`.
template <typename Dispatch>
NetOutcome guarded(const std::string &instance, proto::Err code, Dispatch &&dispatch)
{
    try {
        return dispatch();
    } catch (const std::bad_alloc &) {
        throw;
    } catch (const std::exception &e) {
        logf("instance %s: %s", instance.c_str(), e.what());
        return error(code, e.what());
    }
}
// A request decoded with `decode` into a `Request` and handed to `run`; one that does not
// decode is malformed.
template <typename Request, typename Decode, typename Run>
NetOutcome decoded(proto::Reader &r, Decode &&decode, Run &&run)
{
    Request req{};
    return decode(r, req) ? run(req) : malformed();
}
} // namespace outcome

class NetCommands {
public:
    // `host_id` is what NET_INFO reports and spawned processes get as LN_HOST_ID;
    // `data_port` the port NET_INFO advertises.  `forwarder` must outlive this.
    NetCommands(std::string host_id, uint16_t data_port, fwd::Forwarder &forwarder);

    // True for the message types handle() takes.
    static bool handles(uint8_t type) noexcept;
    NetOutcome handle(const std::string &instance, uint8_t type, proto::Reader &r);

    const std::string &host_id() const noexcept { return host_id_; }

private:
    NetOutcome rings(const std::string &instance, uint8_t type, proto::Reader &r);
    NetOutcome streams(const std::string &instance, uint8_t type, proto::Reader &r);
    // Whether `instance` may add or replace stream `token` on `ring`; else `refusal`.
    bool admit(const std::string &instance, uint64_t token, const std::string &ring,
               NetOutcome &refusal) const;
    // The reply to STREAM_SEND/RECV given the Forwarder's verdict ("" is success).
    NetOutcome added(const std::string &instance, uint64_t token, const std::string &ring,
                     const char *what, const std::string &verdict);
    NetOutcome stream_list(const std::string &instance);
    NetOutcome purge(const std::string &instance);

    std::string host_id_;
    uint16_t data_port_;
    fwd::Forwarder &forwarder_;
    RingTable rings_;
    std::unordered_map<uint64_t, std::string> streams_; // token -> instance
};

} // namespace lnd
