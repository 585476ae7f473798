// The poll loop and the TCP protocol of the daemon (server.hpp).  Order of one round:
// poll -> signals (reap children) -> new connections -> connection input -> process
// descriptors -> timers -> output to connections.  Frames are parsed only from complete
// buffers; the length is checked before a body is awaited, so an oversized frame costs
// nothing but its connection.
#include "server.hpp"

#include <algorithm>
#include <arpa/inet.h>
#include <cerrno>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstring>
#include <exception>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <unistd.h>
#include <vector>

#include "log.hpp"
#include "messages.hpp"

namespace lnd {

using proto::Err;
using proto::Msg;

struct Connection {
    enum class Phase { handshake, ready, closing };
    uint64_t id = 0;
    UniqueFd fd;
    std::string peer;
    Phase phase = Phase::handshake;
    std::string in;
    std::string out;
    uint8_t nonce[proto::kNonceBytes];
    std::string instance;
    Key to_daemon;
    Key to_client;
    uint64_t seq_in = 0;
    uint64_t seq_out = 0;
    double deadline = 0;        // monotonic: handshake or linger ends
    double resource_period = 0; // RESOURCES: seconds between EV_RESOURCES, 0: none
    double resource_due = 0;    // monotonic
    bool shut = false;          // closing: our side is shut down
    bool dead = false;          // to be erased at the end of the round
};

namespace {

uint32_t le32(const char *p) noexcept
{
    const auto *u = reinterpret_cast<const uint8_t *>(p);
    return u[0] | u[1] << 8 | u[2] << 16 | static_cast<uint32_t>(u[3]) << 24;
}

std::string peer_name(const sockaddr_storage &sa)
{
    char host[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0;
    if (sa.ss_family == AF_INET) {
        const auto &in = reinterpret_cast<const sockaddr_in &>(sa);
        ::inet_ntop(AF_INET, &in.sin_addr, host, sizeof host);
        port = ntohs(in.sin_port);
    } else if (sa.ss_family == AF_INET6) {
        const auto &in6 = reinterpret_cast<const sockaddr_in6 &>(sa);
        ::inet_ntop(AF_INET6, &in6.sin6_addr, host, sizeof host);
        port = ntohs(in6.sin6_port);
    }
    return std::string(host) + ":" + std::to_string(port);
}

const char *msg_name(uint8_t type) noexcept
{
    const char *name = wire::name(static_cast<Msg>(type));
    return name ? name : "unknown";
}

} // namespace

Server::Server(Os &os, const Key &key, UniqueFd listener, UniqueFd signals, std::string log_path,
               std::string host_id, std::vector<Feature *> features, double resource_period)
    : os_(os), key_(key), listener_(std::move(listener)), signals_(std::move(signals)),
      log_path_(std::move(log_path)), processes_(os, *this, std::move(host_id)),
      supervisor_(processes_.supervisor()), resource_period_(resource_period)
{
    features_.push_back(&processes_);
    features_.insert(features_.end(), features.begin(), features.end());
}

Server::~Server() = default;

// ---- connections -------------------------------------------------------------------------

void Server::accept_all()
{
    for (;;) {
        sockaddr_storage sa;
        socklen_t len = sizeof sa;
        UniqueFd fd(::accept4(listener_.get(), reinterpret_cast<sockaddr *>(&sa), &len,
                              SOCK_NONBLOCK | SOCK_CLOEXEC));
        if (!fd) {
            if (errno == EMFILE || errno == ENFILE) {
                // The pending connection stays readable: without a pause this would spin.
                logf("accept: %s; not accepting for %.1f s", std::strerror(errno), kAcceptPause);
                accept_paused_until_ = os_.monotonic() + kAcceptPause;
            } else if (errno != EAGAIN && errno != EINTR && errno != ECONNABORTED) {
                logf("accept: %s", std::strerror(errno));
            }
            return;
        }
        std::string peer = peer_name(sa);
        if (conns_.size() >= kMaxConnections && !evict_unauthenticated()) {
            logf("connection from %s refused: %zu connections open", peer.c_str(), conns_.size());
            continue;
        }
        int one = 1, idle = 30, interval = 10, count = 3;
        ::setsockopt(fd.get(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        ::setsockopt(fd.get(), SOL_SOCKET, SO_KEEPALIVE, &one, sizeof one);
        ::setsockopt(fd.get(), IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle);
        ::setsockopt(fd.get(), IPPROTO_TCP, TCP_KEEPINTVL, &interval, sizeof interval);
        ::setsockopt(fd.get(), IPPROTO_TCP, TCP_KEEPCNT, &count, sizeof count);
        auto c = std::make_unique<Connection>();
        c->id = next_conn_++;
        c->fd = std::move(fd);
        c->peer = std::move(peer);
        c->deadline = os_.monotonic() + kHandshakeTimeout;
        random_bytes(c->nonce, sizeof c->nonce);
        wire::DaemonHello hello;
        std::memcpy(hello.magic.data(), proto::kMagic, sizeof proto::kMagic);
        hello.version = proto::kVersion;
        std::memcpy(hello.nonce.data(), c->nonce, sizeof c->nonce);
        proto::Writer w;
        wire::encode(w, hello);
        send(*c, Msg::daemon_hello, 0, w.buffer());
        conns_.emplace(c->id, std::move(c));
    }
}

bool Server::evict_unauthenticated()
{
    // Authenticated connections are never pushed out by newcomers; of the others, one that
    // is closing anyway goes first, else the oldest still in its handshake: a manager's
    // handshake takes one round trip, so the oldest are the ones that do not finish theirs.
    auto victim = conns_.end();
    for (auto it = conns_.begin(); it != conns_.end(); ++it) {
        Connection &c = *it->second;
        if (c.dead || c.phase == Connection::Phase::closing) {
            victim = it;
            break;
        }
        if (c.phase == Connection::Phase::handshake && victim == conns_.end())
            victim = it;
    }
    if (victim == conns_.end())
        return false;
    Connection &c = *victim->second;
    if (!c.dead && c.phase == Connection::Phase::handshake) {
        logf("connection %s closed: its slot is needed, %zu connections open", c.peer.c_str(),
             conns_.size());
        send_error(c, 0, Err::not_authenticated, "connection slot needed by a newer connection");
        flush(c); // best effort: the frame is small
    }
    conns_.erase(victim);
    return true;
}

void Server::send(Connection &c, Msg type, uint32_t req, const std::string &payload)
{
    if (c.dead || (c.phase == Connection::Phase::closing && c.shut))
        return;
    bool tagged = c.phase == Connection::Phase::ready ||
                  (c.phase == Connection::Phase::closing && !c.instance.empty());
    size_t body = proto::kHeaderBytes + payload.size();
    size_t len = body + (tagged ? proto::kTagBytes : 0);
    size_t start = c.out.size();
    proto::Writer head;
    head.u32(static_cast<uint32_t>(len));
    head.u8(static_cast<uint8_t>(type));
    head.u32(req);
    c.out += head.buffer();
    c.out += payload;
    if (tagged) {
        Tag tag;
        frame_tag(c.to_client, c.seq_out++, c.out.data() + start + proto::kLengthBytes, body, tag);
        c.out.append(reinterpret_cast<const char *>(tag), sizeof tag);
    }
    if (c.out.size() > kMaxQueuedBytes)
        drop(c, "it does not read its events fast enough");
}

void Server::send_error(Connection &c, uint32_t req, Err code, const std::string &text)
{
    proto::Writer w;
    wire::encode(w, wire::Error{static_cast<uint16_t>(code), text});
    send(c, Msg::error, req, w.buffer());
}

void Server::refuse(Connection &c, uint32_t req, Err code, const std::string &text)
{
    logf("connection %s%s%s closed: %s", c.peer.c_str(), c.instance.empty() ? "" : " instance ",
         c.instance.c_str(), text.c_str());
    send_error(c, req, code, text);
    c.phase = Connection::Phase::closing;
    c.in.clear();
    c.deadline = os_.monotonic() + kLingerTimeout;
}

void Server::drop(Connection &c, const char *why)
{
    if (c.dead)
        return;
    if (why)
        logf("connection %s%s%s closed: %s", c.peer.c_str(), c.instance.empty() ? "" : " instance ",
             c.instance.c_str(), why);
    c.dead = true;
    c.out.clear();
}

void Server::flush(Connection &c)
{
    while (!c.out.empty() && !c.dead) {
        ssize_t n = ::send(c.fd.get(), c.out.data(), c.out.size(), MSG_NOSIGNAL);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            if (errno != EAGAIN)
                drop(c, nullptr);
            return;
        }
        c.out.erase(0, static_cast<size_t>(n));
    }
    if (c.phase == Connection::Phase::closing && c.out.empty() && !c.shut) {
        // Half-close and wait for the peer to close: closing with unread input would
        // reset the connection and could destroy the error before the peer reads it.
        ::shutdown(c.fd.get(), SHUT_WR);
        c.shut = true;
    }
}

void Server::on_readable(Connection &c)
{
    char buf[65536];
    for (int rounds = 0; rounds < 4 && !c.dead; ++rounds) {
        ssize_t n = ::recv(c.fd.get(), buf, sizeof buf, 0);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            if (errno != EAGAIN)
                drop(c, c.phase == Connection::Phase::closing ? nullptr : "connection error");
            break;
        }
        if (n == 0) {
            drop(c, c.phase == Connection::Phase::ready || c.phase == Connection::Phase::closing
                        ? nullptr
                        : "closed during the handshake");
            if (c.phase == Connection::Phase::ready)
                logf("connection %s instance %s closed by the peer", c.peer.c_str(),
                     c.instance.c_str());
            break;
        }
        if (c.phase == Connection::Phase::closing)
            continue; // discarded until the peer closes
        c.in.append(buf, static_cast<size_t>(n));
        try {
            parse_frames(c);
        } catch (const std::exception &e) { // nothing may escape the protocol boundary
            drop(c, e.what());
        }
        if (static_cast<size_t>(n) < sizeof buf)
            break;
    }
}

void Server::parse_frames(Connection &c)
{
    size_t pos = 0;
    while (!c.dead && c.phase != Connection::Phase::closing) {
        if (c.in.size() - pos < proto::kLengthBytes)
            break;
        uint32_t len = le32(c.in.data() + pos);
        bool tagged = c.phase == Connection::Phase::ready;
        size_t min = proto::kHeaderBytes + (tagged ? proto::kTagBytes : 0);
        size_t max = tagged ? proto::kMaxFrame : proto::kMaxHelloFrame;
        if (len > max) {
            refuse(c, 0, Err::bad_request,
                   "frame of " + std::to_string(len) + " bytes exceeds the limit of " +
                       std::to_string(max) + (tagged ? "" : " before the handshake"));
            return;
        }
        if (len < min) {
            refuse(c, 0, Err::bad_request, "malformed frame of " + std::to_string(len) + " bytes");
            return;
        }
        if (c.in.size() - pos < proto::kLengthBytes + len)
            break;
        const char *body = c.in.data() + pos + proto::kLengthBytes;
        size_t body_len = len - (tagged ? proto::kTagBytes : 0);
        if (tagged) {
            Tag expect;
            frame_tag(c.to_daemon, c.seq_in++, body, body_len, expect);
            if (!tag_equal(expect, reinterpret_cast<const uint8_t *>(body + body_len))) {
                refuse(c, 0, Err::bad_request,
                       "frame with a wrong tag (not from the authenticated peer, altered, "
                       "replayed or out of order)");
                return;
            }
        }
        uint8_t type = static_cast<uint8_t>(body[0]);
        uint32_t req = le32(body + 1);
        proto::Reader r(body + proto::kHeaderBytes, body_len - proto::kHeaderBytes);
        pos += proto::kLengthBytes + len;
        if (c.phase == Connection::Phase::handshake)
            handle_hello(c, type, r);
        else
            handle_request(c, type, req, r);
    }
    if (c.phase == Connection::Phase::closing)
        c.in.clear();
    else
        c.in.erase(0, pos);
}

void Server::handle_hello(Connection &c, uint8_t type, proto::Reader &r)
{
    if (type != static_cast<uint8_t>(Msg::client_hello)) {
        refuse(c, 0, Err::not_authenticated,
               std::string("not authenticated: ") + msg_name(type) +
                   " refused before the handshake");
        return;
    }
    wire::ClientHello hello;
    if (!wire::decode(r, hello) ||
        std::memcmp(hello.magic.data(), proto::kMagic, sizeof proto::kMagic) != 0) {
        refuse(c, 0, Err::bad_request, "malformed CLIENT_HELLO");
        return;
    }
    if (hello.version != proto::kVersion) {
        refuse(c, 0, Err::version,
               "unsupported protocol version " + std::to_string(hello.version) +
                   "; this daemon speaks version " + std::to_string(proto::kVersion));
        return;
    }
    std::string &instance = hello.instance;
    if (!valid_name(instance)) {
        refuse(c, 0, Err::bad_request, "invalid instance name");
        return;
    }
    Session s;
    derive_session(key_, c.nonce, hello.nonce.data(), instance, s);
    if (!tag_equal(s.client_proof, hello.proof.data())) {
        refuse(c, 0, Err::auth_failed,
               "authentication failed (wrong key) for instance " + instance);
        return;
    }
    c.instance = std::move(instance);
    c.to_daemon = s.to_daemon;
    c.to_client = s.to_client;
    wire::AuthOk ok;
    std::memcpy(ok.proof.data(), s.daemon_proof, sizeof s.daemon_proof);
    proto::Writer w;
    wire::encode(w, ok);
    send(c, Msg::auth_ok, 0, w.buffer()); // the last untagged frame
    c.phase = Connection::Phase::ready;
    logf("connection %s authenticated for instance %s", c.peer.c_str(), c.instance.c_str());
}

Feature *Server::owner(uint8_t type) const noexcept
{
    for (Feature *f : features_)
        if (f->handles(type))
            return f;
    return nullptr;
}

void Server::handle_request(Connection &c, uint8_t type, uint32_t req, proto::Reader &r)
{
    auto malformed = [&] {
        refuse(c, req, Err::bad_request, std::string("malformed ") + msg_name(type) + " request");
    };
    if (type == static_cast<uint8_t>(Msg::ping)) {
        if (!r.done())
            return malformed();
        return send(c, Msg::ok, req, {});
    }
    if (type == static_cast<uint8_t>(Msg::resources))
        return resources_request(c, req, r);
    Feature *feature = owner(type);
    if (!feature) {
        refuse(c, req, Err::bad_request, "unknown message type " + std::to_string(type));
        return;
    }
    uint64_t id = next_request_++;
    Outcome out = feature->handle(Request{c.instance, type, id, r});
    switch (out.kind) {
    case Outcome::Kind::malformed:
        return malformed();
    case Outcome::Kind::error:
        return send_error(c, req, out.code, out.text);
    case Outcome::Kind::reply:
        return send(c, out.type, req, out.payload);
    case Outcome::Kind::deferred:
        pending_[id] = {c.id, req};
        return;
    }
}

void Server::broadcast(const std::string &instance, Msg type, const std::string &payload)
{
    for (auto &entry : conns_) {
        Connection &c = *entry.second;
        if (c.phase == Connection::Phase::ready && !c.dead && c.instance == instance)
            send(c, type, 0, payload);
    }
}

// ---- Sink ------------------------------------------------------------------------------

void Server::spawn_result(const Process &p, const Outcome &result)
{
    if (!result.failed())
        logf("instance %s: %s started, pid %d", p.instance().c_str(), p.name().c_str(),
             static_cast<int>(p.pid()));
    else
        logf("instance %s: %s not started: %s", p.instance().c_str(), p.name().c_str(),
             result.text.c_str());
    auto it = pending_.find(p.token());
    if (it == pending_.end())
        return;
    auto [conn_id, req] = it->second;
    pending_.erase(it);
    auto c = conns_.find(conn_id);
    if (c == conns_.end() || c->second->phase != Connection::Phase::ready)
        return; // the requester is gone; LIST shows the outcome
    if (result.failed())
        return send_error(*c->second, req, result.code, result.text);
    proto::Writer w;
    encode_info(w, p);
    send(*c->second, Msg::spawned, req, w.buffer());
}

void Server::line(const Process &p, const Line &line)
{
    proto::Writer w;
    encode_output_event(w, p, line);
    broadcast(p.instance(), Msg::ev_output, w.buffer());
}

void Server::state_changed(const Process &p)
{
    proto::Writer w;
    encode_state_event(w, p);
    broadcast(p.instance(), Msg::ev_state, w.buffer());
}

void Server::exited(const Process &p)
{
    if (p.exit_kind() == proto::ExitKind::signal)
        logf("instance %s: %s (pid %d) killed by signal %d", p.instance().c_str(), p.name().c_str(),
             static_cast<int>(p.pid()), p.exit_value());
    else
        logf("instance %s: %s (pid %d) exited with code %d", p.instance().c_str(), p.name().c_str(),
             static_cast<int>(p.pid()), p.exit_value());
    proto::Writer w;
    encode_exited_event(w, p);
    broadcast(p.instance(), Msg::ev_exited, w.buffer());
}

// ---- resource samples --------------------------------------------------------------------

void Server::resources_request(Connection &c, uint32_t req, proto::Reader &r)
{
    wire::Resources body;
    if (!wire::decode(r, body) || std::isnan(body.period))
        return refuse(c, req, Err::bad_request, "malformed RESOURCES request");
    if (body.period < 0) {
        c.resource_period = 0;
        return send(c, Msg::ok, req, {});
    }
    if (resource_period_ <= 0)
        return send_error(c, req, Err::limit,
                          "resource samples are disabled (ln_daemon --resource-period 0)");
    double period = body.period == 0 ? resource_period_ : body.period;
    c.resource_period = std::min(std::max(period, res::kMinPeriod), res::kMaxPeriod);
    c.resource_due = os_.monotonic(); // the first sample at once: a baseline for the rates
    send(c, Msg::ok, req, {});
}

double Server::resources_due() const noexcept
{
    double due = HUGE_VAL;
    for (const auto &entry : conns_) {
        const Connection &c = *entry.second;
        if (c.resource_period > 0 && c.phase == Connection::Phase::ready)
            due = std::min(due, c.resource_due);
    }
    return due;
}

// One host sample for every connection that is due, and per connection the running processes
// of its instance.  A failure (an unreadable /proc) is logged once and skips the round.
void Server::send_resources(double now)
{
    if (resources_due() > now)
        return;
    Outcome host = sampler_.sample_host(now, sample_);
    if (host.failed()) {
        if (!sample_failed_)
            logf("resource sample failed: %s", host.text.c_str());
        sample_failed_ = true;
    } else {
        sample_failed_ = false;
    }
    char name[256] = "";
    ::gethostname(name, sizeof name - 1);
    sample_.host = name;
    sample_.time = os_.wall();
    for (auto &entry : conns_) {
        Connection &c = *entry.second;
        if (c.resource_period <= 0 || c.phase != Connection::Phase::ready || c.dead ||
            c.resource_due > now)
            continue;
        c.resource_due = std::max(c.resource_due + c.resource_period, now);
        if (host.failed())
            continue;
        size_t n = 0;
        for (const Process *p : supervisor_.list(c.instance)) {
            if (p->state() != State::running && p->state() != State::stopping)
                continue;
            if (n == sample_.processes.size())
                sample_.processes.emplace_back();
            wire::ProcessResources &pr = sample_.processes[n];
            if (sampler_.sample_process(p->pid(), now, pr).failed())
                continue; // gone meanwhile: its exit follows
            pr.name = p->name();
            ++n;
        }
        sample_.processes.resize(n);
        proto::Writer w;
        wire::encode(w, sample_);
        send(c, Msg::ev_resources, 0, w.buffer());
    }
    sampler_.forget_older(now - 2 * res::kMaxPeriod);
}

// ---- the loop ----------------------------------------------------------------------------

void Server::begin_shutdown()
{
    if (++shutdown_signals_ == 1) {
        logf("shutting down: stopping %zu process(es)", supervisor_.alive());
        listener_.reset();
        processes_.stop_all();
    } else {
        logf("second shutdown signal: SIGKILL to every process tree");
        supervisor_.kill_all();
    }
}

void Server::read_signals()
{
    signalfd_siginfo si;
    bool child = false;
    while (::read(signals_.get(), &si, sizeof si) == static_cast<ssize_t>(sizeof si)) {
        switch (si.ssi_signo) {
        case SIGCHLD:
            child = true;
            break;
        case SIGTERM:
        case SIGINT:
            begin_shutdown();
            break;
        case SIGHUP:
            if (!log_path_.empty()) {
                if (Outcome o = log_open(log_path_); o.failed())
                    logf("%s", o.text.c_str());
                else
                    logf("log file reopened");
            }
            reload_key();
            break;
        default:
            break;
        }
    }
    if (child)
        supervisor_.reap();
}

void Server::reload_key_on_hangup(std::string path, std::function<void(const Key &)> apply)
{
    key_path_ = std::move(path);
    key_apply_ = std::move(apply);
}

void Server::reload_key()
{
    if (key_path_.empty())
        return;
    Key fresh;
    if (Outcome o = load_key_file(key_path_, fresh); o.failed()) {
        logf("key file not re-read, the old key stays in use: %s", o.text.c_str());
        return;
    }
    if (std::memcmp(fresh.bytes, key_.bytes, Key::kBytes) == 0) {
        logf("key file re-read: the key is unchanged");
        return;
    }
    key_ = fresh;
    logf("key file re-read: new key %s; streams start again with keys derived from it",
         key_id(key_).c_str());
    if (key_apply_)
        key_apply_(key_);
}

int Server::run()
{
    std::vector<pollfd> fds;
    std::vector<Supervisor::FdRef> proc_refs;
    std::vector<uint64_t> conn_ids;
    for (;;) {
        // Processes still starting when the shutdown began are stopped (or killed) by the
        // supervisor's tick() once they run.
        if (shutdown_signals_ && supervisor_.alive() == 0 && supervisor_.stray_keepers() == 0)
            break;
        fds.clear();
        proc_refs.clear();
        conn_ids.clear();
        fds.push_back({signals_.get(), POLLIN, 0});
        bool accepting = listener_ && os_.monotonic() >= accept_paused_until_;
        fds.push_back({accepting ? listener_.get() : -1, POLLIN, 0}); // -1: ignored
        for (auto &entry : conns_) {
            Connection &c = *entry.second;
            short events = POLLIN;
            if (!c.out.empty())
                events |= POLLOUT;
            fds.push_back({c.fd.get(), events, 0});
            conn_ids.push_back(c.id);
        }
        size_t proc_base = fds.size();
        supervisor_.collect_fds(fds, proc_refs);

        double due = std::min(supervisor_.next_deadline(), resources_due());
        if (listener_ && !accepting)
            due = std::min(due, accept_paused_until_);
        for (auto &entry : conns_)
            if (entry.second->phase != Connection::Phase::ready)
                due = std::min(due, entry.second->deadline);
        int timeout = -1;
        if (due != HUGE_VAL) {
            double ms = std::ceil((due - os_.monotonic()) * 1000.0);
            timeout = ms <= 0 ? 0 : ms > 60000 ? 60000 : static_cast<int>(ms);
        }
        int n = ::poll(fds.data(), fds.size(), timeout);
        if (n < 0 && errno != EINTR) {
            logf("poll: %s", std::strerror(errno));
            return 1;
        }
        if (n > 0) {
            if (fds[0].revents)
                read_signals();
            if (fds[1].revents && accepting && listener_)
                accept_all();
            for (size_t i = 0; i < conn_ids.size(); ++i) {
                short rev = fds[2 + i].revents;
                auto it = conns_.find(conn_ids[i]);
                if (!rev || it == conns_.end())
                    continue;
                if (rev & (POLLIN | POLLHUP | POLLERR))
                    on_readable(*it->second);
            }
            for (size_t i = 0; i < proc_refs.size(); ++i)
                if (fds[proc_base + i].revents)
                    supervisor_.on_fd(proc_refs[i]);
        }
        supervisor_.tick();
        double now = os_.monotonic();
        send_resources(now);
        for (auto it = conns_.begin(); it != conns_.end();) {
            Connection &c = *it->second;
            if (!c.dead && c.phase == Connection::Phase::handshake && now >= c.deadline)
                refuse(c, 0, Err::not_authenticated, "no handshake within the time limit");
            else if (!c.dead && c.phase == Connection::Phase::closing && now >= c.deadline)
                drop(c, nullptr);
            if (!c.dead)
                flush(c);
            if (c.dead)
                it = conns_.erase(it);
            else
                ++it;
        }
    }
    for (auto &entry : conns_) // best effort: the last events
        flush(*entry.second);
    // Loggers logged what the processes published while they stopped.
    for (Feature *f : features_)
        f->shutdown();
    logf("every process has exited; daemon ends");
    return 0;
}

} // namespace lnd
