// The daemon's one error convention.  Every function of the daemon that can be refused or can
// fail returns an Outcome: a reply (success; the empty OK reply when there is nothing to say),
// an error (a protocol code from daemon.schema and a sentence naming what was refused), a
// malformed request, or an answer that follows later.  Results other than the reply travel in
// out-parameters.  Request handlers hand their Outcome to the server unchanged; start-up code
// prints its text.  Exceptions are left to constructors that cannot acquire their resource
// (sockets, threads, eventfds) and to bad_alloc: `outcome::guarded` turns the former into an
// Outcome where a request meets them; nothing is thrown across the protocol boundary.
// Two things are not errors in this sense and keep their own types: the byte-level socket
// helpers of the forwarding threads return an I/O state (fwd::Io: closed, timed out, stopped
// are outcomes the caller acts on), and a pull topic's per-packet path records its problem
// in a fixed buffer (ErrorText, pull_reply.hpp) because it must not allocate.
#pragma once

#include <cstdint>
#include <exception>
#include <new>
#include <string>
#include <utility>

#include "log.hpp"
#include "protocol.hpp"

namespace lnd {

struct [[nodiscard]] Outcome {
    enum class Kind { reply, error, malformed, deferred };
    Kind kind = Kind::reply;
    proto::Msg type = proto::Msg::ok;          // reply
    std::string payload;                       // reply
    proto::Err code = proto::Err::bad_request; // error
    std::string text;                          // error

    bool failed() const noexcept { return kind == Kind::error || kind == Kind::malformed; }
};

namespace outcome {
inline Outcome ok() { return {}; }
inline Outcome reply(proto::Msg type, std::string payload)
{
    Outcome o;
    o.type = type;
    o.payload = std::move(payload);
    return o;
}
inline Outcome error(proto::Err code, std::string text)
{
    Outcome o;
    o.kind = Outcome::Kind::error;
    o.code = code;
    o.text = std::move(text);
    return o;
}
inline Outcome malformed()
{
    Outcome o;
    o.kind = Outcome::Kind::malformed;
    return o;
}
// The request was taken; its reply is sent later under the request's id (SPAWN: once the
// keeper has reported).
inline Outcome deferred()
{
    Outcome o;
    o.kind = Outcome::Kind::deferred;
    return o;
}
// `failure` with "`prefix`" in front of its text.
inline Outcome prefixed(const std::string &prefix, Outcome failure)
{
    failure.text.insert(0, prefix);
    return failure;
}
// Runs `dispatch` where constructors may throw: bad_alloc propagates (the connection is
// dropped, Server::on_readable); any other exception (a thread or an eventfd that could not be
// made) is logged for `instance` and becomes error `code`.
template <typename Dispatch>
Outcome guarded(const std::string &instance, proto::Err code, Dispatch &&dispatch)
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
// A request decoded with `decode` into a `Message` and handed to `run`; one that does not
// decode is malformed.
template <typename Message, typename Decode, typename Run>
Outcome decoded(proto::Reader &r, Decode &&decode, Run &&run)
{
    Message message{};
    return decode(r, message) ? run(message) : malformed();
}
} // namespace outcome

} // namespace lnd
