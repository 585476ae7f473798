// The topic rings this daemon administers for managers on other hosts, through libln's
// ln_ring_admin_* functions (docs/daemon.md, "Rings and forwarding").  Each handle maps only
// a segment's header.  A segment belongs to the instance whose namespace its name lies in,
// "/ln.<sanitized instance>."; handles outlive the manager's connection and are closed when
// the table goes (daemon exit), but segments are only unlinked on request, so a restarted
// daemon can adopt them again.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "net_messages.hpp"
#include "outcome.hpp"
#include "protocol.hpp"

struct ln_ring_admin;

namespace lnd {

constexpr size_t kMaxRings = 16384;        // handles per daemon, all instances
constexpr double kMaxRetireTimeout = 10.0; // RING_RETIRE blocks the poll loop that long at most

// The instance name as segment names carry it (libln's ln_name_instance, naming.h: every
// character other than A-Z a-z 0-9 _ - becomes one '_').
std::string sanitize_instance(const std::string &instance);
// "/ln.<sanitized instance>."
std::string ring_prefix(const std::string &instance);
// Whether `name` is a segment name in the instance's namespace: the prefix, then at least
// one more byte and no further '/'; else error `code` with a sentence.
Outcome ring_in_namespace(const std::string &instance, const std::string &name,
                          proto::Err code = proto::Err::ring_failed);

class RingTable {
public:
    RingTable();
    ~RingTable(); // closes every handle; unlinks nothing
    RingTable(const RingTable &) = delete;
    RingTable &operator=(const RingTable &) = delete;

    // Each refuses with error ring_failed and a sentence, or with libln's failure (then with
    // ln_last_error()'s text); create() with error limit when the table is full.
    Outcome create(const std::string &instance, const RingCreateRequest &req);
    Outcome retire(const std::string &instance, const RingRetireRequest &req);
    Outcome reader(const std::string &instance, const RingReaderRequest &req);
    Outcome counts(const std::string &instance, const RingCountsRequest &req);
    Outcome write_seq(const std::string &instance, const std::string &name, uint64_t &seq);
    // Closes the handle if there is one and unlinks the segment (gone already is fine).
    Outcome remove(const std::string &instance, const std::string &name);
    // Closes every handle of the instance's namespace and unlinks every segment in it,
    // held or not; `count` is how many segments were unlinked.
    Outcome purge(const std::string &instance, uint64_t &count);

    size_t size() const noexcept { return rings_.size(); }

private:
    struct Closer {
        void operator()(ln_ring_admin *admin) const noexcept;
    };
    using Handle = std::unique_ptr<ln_ring_admin, Closer>;

    // The held handle of `name` in `admin`; refused outside the namespace or when not held.
    Outcome find(const std::string &instance, const std::string &name, ln_ring_admin *&admin);

    std::map<std::string, Handle> rings_; // by segment name
};

} // namespace lnd
