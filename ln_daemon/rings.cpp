// RingTable (rings.hpp): ownership and namespace checks around libln's ring administration.
// Every libln failure is reported as what was being done plus ln_last_error(), the text
// with errno and names that libln keeps for the calling thread.
#include "rings.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <ln/ln.h>
#include <ln_admin.h>
#include <naming.h>
#include <sys/mman.h>
#include <sys/stat.h>

#include "fd.hpp"

namespace lnd {

using outcome::ok;

namespace {

Outcome refused(std::string text)
{
    return outcome::error(proto::Err::ring_failed, std::move(text));
}

Outcome libln_error(const std::string &what, int rc)
{
    return refused(what + ": " + ln_error_name(rc) + ": " + ln_last_error());
}

// A segment that exists must have the size its geometry gives and the layout asked for,
// else it is some other ring.  (A tap checks the layout: the admin handle cannot.)
Outcome check_geometry(const RingCreateRequest &req)
{
    UniqueFd fd(::shm_open(req.name.c_str(), O_RDONLY | O_CLOEXEC, 0));
    struct stat st;
    if (!fd || ::fstat(fd.get(), &st) != 0)
        return ok(); // gone meanwhile: the next call on it says so
    uint64_t want = ln_ring_segment_size(req.message_size, req.slots);
    if (static_cast<uint64_t>(st.st_size) != want)
        return refused("segment " + req.name + " exists with " + std::to_string(st.st_size) +
                       " bytes, not the " + std::to_string(want) + " of " +
                       std::to_string(req.slots) + " slots of " + std::to_string(req.message_size) +
                       " bytes");
    ln_ring_tap *tap = nullptr;
    int rc =
        ln_ring_tap_open(&tap, req.name.c_str(), req.layout_hash, req.message_size, LN_TAP_NEWEST);
    if (rc == LN_OK)
        ln_ring_tap_close(tap);
    if (rc == LN_ELAYOUT)
        return libln_error("adopting segment " + req.name, rc);
    return ok(); // anything else is not a mismatch of this ring (e.g. a successor is gone)
}

} // namespace

std::string sanitize_instance(const std::string &instance)
{
    std::string out(instance.size() + 1, '\0');
    out.resize(ln_name_instance(instance.c_str(), out.data(), out.size()));
    return out;
}

std::string ring_prefix(const std::string &instance)
{
    std::string out(instance.size() + 8, '\0');
    if (ln_name_segment_prefix(instance.c_str(), out.data(), out.size()) != LN_OK)
        return {};
    out.resize(std::strlen(out.c_str()));
    return out;
}

Outcome ring_in_namespace(const std::string &instance, const std::string &name, proto::Err code)
{
    std::string prefix = ring_prefix(instance);
    if (name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
        name.find('/', 1) == std::string::npos && name.find('\0') == std::string::npos)
        return ok();
    return outcome::error(code, "ring name '" + name + "' is not in the namespace of instance " +
                                    instance + " (" + prefix + "*)");
}

void RingTable::Closer::operator()(ln_ring_admin *admin) const noexcept
{
    ln_ring_admin_close(admin);
}

RingTable::RingTable() = default;
RingTable::~RingTable() = default;

Outcome RingTable::find(const std::string &instance, const std::string &name, ln_ring_admin *&admin)
{
    if (Outcome o = ring_in_namespace(instance, name); o.failed())
        return o;
    auto it = rings_.find(name);
    if (it == rings_.end())
        return refused("this daemon holds no ring " + name + " (create or adopt it first)");
    admin = it->second.get();
    return ok();
}

Outcome RingTable::create(const std::string &instance, const RingCreateRequest &req)
{
    if (Outcome o = ring_in_namespace(instance, req.name); o.failed())
        return o;
    auto held = rings_.find(req.name);
    if (held != rings_.end()) {
        UniqueFd fd(::shm_open(req.name.c_str(), O_RDONLY | O_CLOEXEC, 0));
        if (!fd && errno == ENOENT) {
            rings_.erase(held); // unlinked behind our back: the handle is stale
        } else if (req.adopt) { // still held from before the manager went away
            return check_geometry(req);
        } else {
            return refused("ring " + req.name + " exists already");
        }
    }
    if (rings_.size() >= kMaxRings)
        return outcome::error(proto::Err::limit,
                              "too many rings (" + std::to_string(kMaxRings) + ") on this daemon");
    ln_ring_admin *raw = nullptr;
    if (req.adopt) {
        int rc = ln_ring_admin_open(&raw, req.name.c_str());
        if (rc == LN_OK) {
            Handle handle(raw);
            if (Outcome o = check_geometry(req); o.failed())
                return o;
            rings_.emplace(req.name, std::move(handle));
            return ok();
        }
        if (rc != LN_ENOTFOUND)
            return libln_error("adopting segment " + req.name, rc);
    }
    int rc = ln_ring_admin_create(&raw, req.name.c_str(), req.topic.c_str(), req.md_name.c_str(),
                                  req.layout_hash, req.message_size, req.slots);
    if (rc != LN_OK)
        return libln_error("creating segment " + req.name + " with " + std::to_string(req.slots) +
                               " slots of " + std::to_string(req.message_size) + " bytes",
                           rc);
    rings_.emplace(req.name, Handle(raw));
    return ok();
}

Outcome RingTable::retire(const std::string &instance, const RingRetireRequest &req)
{
    ln_ring_admin *old = nullptr;
    if (Outcome o = find(instance, req.old_name, old); o.failed())
        return o;
    ln_ring_admin *successor = nullptr;
    if (Outcome o = find(instance, req.successor, successor); o.failed())
        return o;
    if (old == successor)
        return refused("a ring cannot be its own successor");
    if (!std::isfinite(req.timeout) || req.timeout < 0 || req.timeout > kMaxRetireTimeout)
        return refused("retire timeout " + std::to_string(req.timeout) + " is not in 0.." +
                       std::to_string(kMaxRetireTimeout) + " s");
    int rc = ln_ring_admin_retire(old, successor, req.successor.c_str(), req.timeout);
    if (rc != LN_OK)
        return libln_error("retiring " + req.old_name + " into " + req.successor, rc);
    return ok();
}

Outcome RingTable::reader(const std::string &instance, const RingReaderRequest &req)
{
    ln_ring_admin *admin = nullptr;
    if (Outcome o = find(instance, req.name, admin); o.failed())
        return o;
    int rc = req.reserve ? ln_ring_admin_reserve_reader(admin, req.index, req.pid, req.buffers)
                         : ln_ring_admin_release_reader(admin, req.index);
    if (rc != LN_OK)
        return libln_error((req.reserve ? "reserving reader slot " : "releasing reader slot ") +
                               std::to_string(req.index) + " of " + req.name,
                           rc);
    return ok();
}

Outcome RingTable::counts(const std::string &instance, const RingCountsRequest &req)
{
    ln_ring_admin *admin = nullptr;
    if (Outcome o = find(instance, req.name, admin); o.failed())
        return o;
    int rc = ln_ring_admin_set_counts(admin, req.publishers, req.subscribers);
    if (rc != LN_OK)
        return libln_error("setting the port counts of " + req.name, rc);
    return ok();
}

Outcome RingTable::write_seq(const std::string &instance, const std::string &name, uint64_t &seq)
{
    ln_ring_admin *admin = nullptr;
    if (Outcome o = find(instance, name, admin); o.failed())
        return o;
    int rc = ln_ring_admin_write_seq(admin, &seq);
    if (rc != LN_OK)
        return libln_error("reading the sequence number of " + name, rc);
    return ok();
}

Outcome RingTable::remove(const std::string &instance, const std::string &name)
{
    if (Outcome o = ring_in_namespace(instance, name); o.failed())
        return o;
    rings_.erase(name);
    int rc = ln_ring_admin_unlink(name.c_str());
    if (rc != LN_OK)
        return libln_error("unlinking segment " + name, rc);
    return ok();
}

Outcome RingTable::purge(const std::string &instance, uint64_t &count)
{
    std::string prefix = ring_prefix(instance);
    for (auto it = rings_.lower_bound(prefix);
         it != rings_.end() && it->first.compare(0, prefix.size(), prefix) == 0;)
        it = rings_.erase(it);
    int rc = ln_ring_admin_purge_instance(sanitize_instance(instance).c_str());
    if (rc < 0)
        return libln_error("removing the segments " + prefix + "*", rc);
    count = static_cast<uint64_t>(rc);
    return ok();
}

} // namespace lnd
