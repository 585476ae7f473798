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

namespace {

std::string libln_error(const std::string &what, int rc)
{
    return what + ": " + ln_error_name(rc) + ": " + ln_last_error();
}

// A segment that exists must have the size its geometry gives and the layout asked for,
// else it is some other ring.  (A tap checks the layout: the admin handle cannot.)
bool check_geometry(const RingCreateRequest &req, std::string &error)
{
    UniqueFd fd(::shm_open(req.name.c_str(), O_RDONLY | O_CLOEXEC, 0));
    struct stat st;
    if (!fd || ::fstat(fd.get(), &st) != 0)
        return true; // gone meanwhile: the next call on it says so
    uint64_t want = ln_ring_segment_size(req.message_size, req.slots);
    if (static_cast<uint64_t>(st.st_size) != want) {
        error = "segment " + req.name + " exists with " + std::to_string(st.st_size) +
                " bytes, not the " + std::to_string(want) + " of " +
                std::to_string(req.slots) + " slots of " + std::to_string(req.message_size) +
                " bytes";
        return false;
    }
    ln_ring_tap *tap = nullptr;
    int rc = ln_ring_tap_open(&tap, req.name.c_str(), req.layout_hash, req.message_size,
                              LN_TAP_NEWEST);
    if (rc == LN_OK)
        ln_ring_tap_close(tap);
    if (rc == LN_ELAYOUT) {
        error = libln_error("adopting segment " + req.name, rc);
        return false;
    }
    return true; // anything else is not a mismatch of this ring (e.g. a successor is gone)
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

bool ring_in_namespace(const std::string &instance, const std::string &name,
                       std::string &error)
{
    std::string prefix = ring_prefix(instance);
    if (name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
        name.find('/', 1) == std::string::npos && name.find('\0') == std::string::npos)
        return true;
    error = "ring name '" + name + "' is not in the namespace of instance " + instance + " (" +
            prefix + "*)";
    return false;
}

void RingTable::Closer::operator()(ln_ring_admin *admin) const noexcept
{
    ln_ring_admin_close(admin);
}

RingTable::RingTable() = default;
RingTable::~RingTable() = default;

ln_ring_admin *RingTable::find(const std::string &instance, const std::string &name,
                               std::string &error)
{
    if (!ring_in_namespace(instance, name, error))
        return nullptr;
    auto it = rings_.find(name);
    if (it == rings_.end()) {
        error = "this daemon holds no ring " + name + " (create or adopt it first)";
        return nullptr;
    }
    return it->second.get();
}

bool RingTable::create(const std::string &instance, const RingCreateRequest &req, bool &limit,
                       std::string &error)
{
    limit = false;
    if (!ring_in_namespace(instance, req.name, error))
        return false;
    auto held = rings_.find(req.name);
    if (held != rings_.end()) {
        UniqueFd fd(::shm_open(req.name.c_str(), O_RDONLY | O_CLOEXEC, 0));
        if (!fd && errno == ENOENT) {
            rings_.erase(held); // unlinked behind our back: the handle is stale
        } else if (req.adopt) { // still held from before the manager went away
            return check_geometry(req, error);
        } else {
            error = "ring " + req.name + " exists already";
            return false;
        }
    }
    if (rings_.size() >= kMaxRings) {
        limit = true;
        error = "too many rings (" + std::to_string(kMaxRings) + ") on this daemon";
        return false;
    }
    ln_ring_admin *raw = nullptr;
    if (req.adopt) {
        int rc = ln_ring_admin_open(&raw, req.name.c_str());
        if (rc == LN_OK) {
            Handle handle(raw);
            if (!check_geometry(req, error))
                return false;
            rings_.emplace(req.name, std::move(handle));
            return true;
        }
        if (rc != LN_ENOTFOUND) {
            error = libln_error("adopting segment " + req.name, rc);
            return false;
        }
    }
    int rc = ln_ring_admin_create(&raw, req.name.c_str(), req.topic.c_str(), req.md_name.c_str(),
                                  req.layout_hash, req.message_size, req.slots);
    if (rc != LN_OK) {
        error = libln_error("creating segment " + req.name + " with " +
                                std::to_string(req.slots) + " slots of " +
                                std::to_string(req.message_size) + " bytes",
                            rc);
        return false;
    }
    rings_.emplace(req.name, Handle(raw));
    return true;
}

bool RingTable::retire(const std::string &instance, const RingRetireRequest &req,
                       std::string &error)
{
    ln_ring_admin *old = find(instance, req.old_name, error);
    if (!old)
        return false;
    ln_ring_admin *successor = find(instance, req.successor, error);
    if (!successor)
        return false;
    if (old == successor) {
        error = "a ring cannot be its own successor";
        return false;
    }
    if (!std::isfinite(req.timeout) || req.timeout < 0 || req.timeout > kMaxRetireTimeout) {
        error = "retire timeout " + std::to_string(req.timeout) + " is not in 0.." +
                std::to_string(kMaxRetireTimeout) + " s";
        return false;
    }
    int rc = ln_ring_admin_retire(old, successor, req.successor.c_str(), req.timeout);
    if (rc != LN_OK) {
        error = libln_error("retiring " + req.old_name + " into " + req.successor, rc);
        return false;
    }
    return true;
}

bool RingTable::reader(const std::string &instance, const RingReaderRequest &req,
                       std::string &error)
{
    ln_ring_admin *admin = find(instance, req.name, error);
    if (!admin)
        return false;
    int rc = req.reserve ? ln_ring_admin_reserve_reader(admin, req.index, req.pid, req.buffers)
                         : ln_ring_admin_release_reader(admin, req.index);
    if (rc != LN_OK) {
        error = libln_error((req.reserve ? "reserving reader slot " : "releasing reader slot ") +
                                std::to_string(req.index) + " of " + req.name,
                            rc);
        return false;
    }
    return true;
}

bool RingTable::counts(const std::string &instance, const RingCountsRequest &req,
                       std::string &error)
{
    ln_ring_admin *admin = find(instance, req.name, error);
    if (!admin)
        return false;
    int rc = ln_ring_admin_set_counts(admin, req.publishers, req.subscribers);
    if (rc != LN_OK) {
        error = libln_error("setting the port counts of " + req.name, rc);
        return false;
    }
    return true;
}

bool RingTable::write_seq(const std::string &instance, const std::string &name, uint64_t &seq,
                          std::string &error)
{
    ln_ring_admin *admin = find(instance, name, error);
    if (!admin)
        return false;
    int rc = ln_ring_admin_write_seq(admin, &seq);
    if (rc != LN_OK) {
        error = libln_error("reading the sequence number of " + name, rc);
        return false;
    }
    return true;
}

bool RingTable::remove(const std::string &instance, const std::string &name, std::string &error)
{
    if (!ring_in_namespace(instance, name, error))
        return false;
    rings_.erase(name);
    int rc = ln_ring_admin_unlink(name.c_str());
    if (rc != LN_OK) {
        error = libln_error("unlinking segment " + name, rc);
        return false;
    }
    return true;
}

bool RingTable::purge(const std::string &instance, uint64_t &count, std::string &error)
{
    std::string prefix = ring_prefix(instance);
    for (auto it = rings_.lower_bound(prefix);
         it != rings_.end() && it->first.compare(0, prefix.size(), prefix) == 0;)
        it = rings_.erase(it);
    int rc = ln_ring_admin_purge_instance(sanitize_instance(instance).c_str());
    if (rc < 0) {
        error = libln_error("removing the segments " + prefix + "*", rc);
        return false;
    }
    count = static_cast<uint64_t>(rc);
    return true;
}

} // namespace lnd
