// SendStream: what the stream table knows of a sending stream, whichever its transport:
// start its threads, ask them to stop, join them, read its counters; and the step both
// transports start every sample with, taking it out of the ring.
#pragma once

#include <string>

#include "forward.hpp"
#include "forward_stats.hpp"
#include "forward_tap.hpp"

namespace lnd::fwd {

class SendStream {
public:
    explicit SendStream(const SendSpec &spec)
        : spec_(spec), counters_(spec.token, true, spec.transport, spec.transport == Transport::udp)
    {
        bool v6 = spec.host.find(':') != std::string::npos; // an IPv6 literal
        counters_.set_peer((v6 ? "[" + spec.host + "]" : spec.host) + ":" +
                           std::to_string(spec.port));
    }
    virtual ~SendStream() = default;
    SendStream(const SendStream &) = delete;
    SendStream &operator=(const SendStream &) = delete;

    virtual void start() = 0;
    // Asks the threads to stop and returns at once; join() waits for them.  Stopping
    // several streams first and joining them after lets their waits overlap.
    virtual void stop() noexcept = 0;
    virtual void join() noexcept = 0;

    StreamStats stats() const { return counters_.snapshot(); }
    const SendSpec &spec() const noexcept { return spec_; }

protected:
    enum class Next { sample, none, stop };
    // The next sample of `tap` into buf (read_tap, sleeping up to 0.1 s so that a stop is
    // noticed soon): `sample` with info set, the tap's segment noted and the samples it
    // skipped counted as drops; `none` if none came or the ring could not be read (the
    // error recorded, after a pause); `stop` once the stream is to end.
    Next next_sample(ln_ring_tap *tap, void *buf, ln_sample_info &info, int64_t spin_ns,
                     const StopSignal &stop)
    {
        return judge(read_tap(tap, buf, info, spin_ns, 0.1, stop), tap, info, stop);
    }
    // The same, the sample left in the ring (borrow_tap): release it with ln_ring_tap_release.
    Next next_borrowed(ln_ring_tap *tap, const void **payload, ln_sample_info &info,
                       int64_t spin_ns, const StopSignal &stop)
    {
        return judge(borrow_tap(tap, payload, info, spin_ns, 0.1, stop), tap, info, stop);
    }

    const SendSpec spec_;
    StreamCounters counters_;

private:
    Next judge(int rc, ln_ring_tap *tap, const ln_sample_info &info, const StopSignal &stop)
    {
        if (rc == LN_ETIMEOUT)
            return Next::none;
        if (rc != LN_OK) {
            counters_.set_error(std::string("cannot read the ring: ") + ln_last_error());
            return stop.sleep_for(100) ? Next::stop : Next::none;
        }
        counters_.note_segment(ln_ring_tap_segment(tap));
        if (info.overruns)
            StreamCounters::add(counters_.drops, info.overruns);
        return Next::sample;
    }
};

} // namespace lnd::fwd
