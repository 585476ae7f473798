// UdpGuard (forward_udp_guard.hpp).  Senders choose salts that grow (the wall clock, see
// UdpSender::fresh_salt), so a recording of an earlier sender incarnation is never taken
// again once a later one was seen.
#include "forward_udp_guard.hpp"

#include <cstring>
#include <new>

namespace lnd::fwd {

const char *UdpGuard::admit(wire::Fragment &f, uint8_t *datagram) noexcept
{
    using sec::Suite;
    const auto suite = static_cast<Suite>(f.suite);
    if (!sec::suite_accepted(level_, suite))
        return "its protection does not match the stream's security level";
    if (suite == Suite::none)
        return nullptr;
    uint8_t *payload = datagram + wire::kFragmentHeaderSize;
    if (box_ && f.salt == salt_ && box_->suite() == suite) {
        switch (window_.check(f.counter)) {
        case sec::ReplayWindow::Verdict::duplicate:
            return "replayed (counter already seen)";
        case sec::ReplayWindow::Verdict::too_old:
            return "too old for the replay window";
        case sec::ReplayWindow::Verdict::invalid:
            return "counter out of range";
        case sec::ReplayWindow::Verdict::fresh:
            break;
        }
        if (!box_->open(f.counter, datagram, wire::kFragmentHeaderSize, payload, f.length, payload,
                        f.tag))
            return "authentication failed";
        window_.accept(f.counter);
        return nullptr;
    }
    if (box_ && f.salt <= salt_)
        return "a salt older than the sender's current one";
    if (f.counter == 0 || f.counter > sec::kMaxCounter)
        return "counter out of range";
    uint8_t salt[8];
    std::memcpy(salt, datagram + 48, sizeof salt); // Fragment::salt (forward_wire.cpp)
    Key k;
    sec::sub_key(key_, "udp salt", salt, sizeof salt, k);
    std::unique_ptr<sec::Box> box(new (std::nothrow) sec::Box(k, suite));
    if (!box)
        return "no memory for a new salt's key";
    if (!box->open(f.counter, datagram, wire::kFragmentHeaderSize, payload, f.length, payload,
                   f.tag))
        return "authentication failed";
    salt_ = f.salt;
    box_ = std::move(box);
    window_.reset();
    window_.accept(f.counter);
    return nullptr;
}

} // namespace lnd::fwd
