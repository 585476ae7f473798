// Tap: the one owner of an ln_ring_tap (libln's handle for reading samples out of a ring or
// writing them in under their original sequence numbers); closes it in the destructor.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include <ln/ln.h>
#include <ln_admin.h>

#include "forward_net.hpp"
#include "outcome.hpp"

namespace lnd::fwd {

struct TapCloser {
    void operator()(ln_ring_tap *tap) const noexcept { ln_ring_tap_close(tap); }
};
using Tap = std::unique_ptr<ln_ring_tap, TapCloser>;

// Opens a tap on `ring` (LN_TAP_EVERY or LN_TAP_NEWEST) into `out`; refused with libln's
// text as error stream_failed.
inline Outcome open_tap(Tap &out, const std::string &ring, uint64_t layout_hash,
                        uint64_t message_size, unsigned mode)
{
    ln_ring_tap *tap = nullptr;
    int rc = ln_ring_tap_open(&tap, ring.c_str(), layout_hash, message_size, mode);
    if (rc != LN_OK)
        return outcome::error(proto::Err::stream_failed,
                              "cannot open ring '" + ring + "': " + ln_last_error());
    out.reset(tap);
    return outcome::ok();
}

// One read of a tap with libln's code as the result (LN_ETIMEOUT if none came): polls with
// `read(0)`, yielding the CPU, for up to spin_ns (a sample that comes that soon costs no futex
// wake-up; a stop ends the polling), then `read(timeout)` sleeps up to `timeout` seconds.
template <typename Read>
int poll_tap(Read &&read, int64_t spin_ns, double timeout, const StopSignal &stop)
{
    using Clock = std::chrono::steady_clock;
    if (spin_ns > 0) {
        for (auto end = Clock::now() + std::chrono::nanoseconds(spin_ns); !stop.raised();) {
            int rc = read(0.0);
            if (rc != LN_ETIMEOUT || Clock::now() >= end)
                return rc == LN_ETIMEOUT ? read(timeout) : rc;
            std::this_thread::yield();
        }
    }
    return read(timeout);
}

// The next sample copied into buf.
inline int read_tap(ln_ring_tap *tap, void *buf, ln_sample_info &info, int64_t spin_ns,
                    double timeout, const StopSignal &stop)
{
    return poll_tap([&](double t) { return ln_ring_tap_read(tap, buf, &info, t); }, spin_ns,
                    timeout, stop);
}

// The next sample left in the ring (*payload; ln_ring_tap_release says whether it stayed intact).
inline int borrow_tap(ln_ring_tap *tap, const void **payload, ln_sample_info &info, int64_t spin_ns,
                      double timeout, const StopSignal &stop)
{
    return poll_tap([&](double t) { return ln_ring_tap_borrow(tap, payload, &info, t); }, spin_ns,
                    timeout, stop);
}

} // namespace lnd::fwd
