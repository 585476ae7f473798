// Processes (processes.hpp): decodes each process request and carries it out on the
// Supervisor; every refusal comes from the Supervisor or the Process it names.
#include "processes.hpp"

#include <utility>

#include "log.hpp"
#include "messages.hpp"
#include "spec.hpp"

namespace lnd {

using outcome::decoded;
using outcome::malformed;
using outcome::ok;
using outcome::reply;
using proto::Err;
using proto::Msg;

namespace {

template <typename Message>
bool decode_wire(proto::Reader &r, Message &m)
{
    return wire::decode(r, m);
}

} // namespace

Processes::Processes(Os &os, Sink &sink, std::string host_id)
    : supervisor_(os, sink), host_id_(std::move(host_id))
{}

bool Processes::handles(uint8_t type) const noexcept
{
    switch (static_cast<Msg>(type)) {
    case Msg::spawn:
    case Msg::stop:
    case Msg::forget:
    case Msg::output:
    case Msg::signal:
    case Msg::list:
        return true;
    default:
        return false;
    }
}

Outcome Processes::handle(const Request &req)
{
    const std::string &in = req.instance;
    proto::Reader &r = req.body;
    switch (static_cast<Msg>(req.type)) {
    case Msg::spawn:
        return decoded<SpawnRequest>(r, decode_spawn, [&](auto &q) { return spawn(req, q); });
    case Msg::stop:
        return decoded<wire::Stop>(r, decode_wire<wire::Stop>,
                                   [&](auto &q) { return stop(in, q); });
    case Msg::forget:
        return decoded<wire::Forget>(r, decode_wire<wire::Forget>,
                                     [&](auto &q) { return forget(in, q); });
    case Msg::output:
        return decoded<wire::Output>(r, decode_wire<wire::Output>,
                                     [&](auto &q) { return output(in, q); });
    case Msg::signal:
        return decoded<wire::Signal>(r, decode_wire<wire::Signal>,
                                     [&](auto &q) { return signal(in, q); });
    case Msg::list:
        return decoded<wire::List>(r, decode_wire<wire::List>, [&](auto &) { return list(in); });
    default:
        return malformed(); // not reached: handles() admits only the types above
    }
}

void Processes::stop_all()
{
    closing_ = true;
    supervisor_.stop_all();
}

Outcome Processes::spawn(const Request &req, SpawnRequest &spawn)
{
    // Clients report the host they run on; this daemon's id names this host.
    env_default(spawn.env, "LN_HOST_ID", host_id_);
    if (closing_)
        return outcome::error(Err::spawn_failed, "the daemon is shutting down");
    Outcome o = supervisor_.spawn(req.instance, spawn, req.id);
    if (!o.failed())
        logf("instance %s: starting %s", req.instance.c_str(), spawn.name.c_str());
    return o;
}

Outcome Processes::stop(const std::string &instance, const wire::Stop &stop)
{
    Process *p = nullptr;
    if (Outcome o = supervisor_.find(instance, stop.name, p); o.failed())
        return o;
    if (Outcome o = p->stop(); o.failed())
        return o;
    logf("instance %s: stopping %s (pid %d)", instance.c_str(), stop.name.c_str(),
         static_cast<int>(p->pid()));
    return ok();
}

Outcome Processes::forget(const std::string &instance, const wire::Forget &forget)
{
    return supervisor_.forget(instance, forget.name);
}

Outcome Processes::output(const std::string &instance, const wire::Output &output)
{
    Process *p = nullptr;
    if (Outcome o = supervisor_.find(instance, output.name, p); o.failed())
        return o;
    proto::Writer w;
    encode_lines(w, *p, output.lines, proto::kMaxFrame - 64);
    return reply(Msg::output_lines, w.buffer());
}

Outcome Processes::signal(const std::string &instance, const wire::Signal &signal)
{
    Process *p = nullptr;
    if (Outcome o = supervisor_.find(instance, signal.name, p); o.failed())
        return o;
    return p->send_signal(signal.signal, signal.group);
}

Outcome Processes::list(const std::string &instance)
{
    wire::ProcessList list;
    for (const Process *p : supervisor_.list(instance))
        list.processes.push_back(process_info(*p));
    proto::Writer w;
    wire::encode(w, list);
    return reply(Msg::process_list, w.buffer());
}

} // namespace lnd
