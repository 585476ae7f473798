// Tap: the one owner of an ln_ring_tap (libln's handle for reading samples out of a ring or
// writing them in under their original sequence numbers); closes it in the destructor.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <ln/ln.h>

namespace lnd::fwd {

struct TapCloser {
    void operator()(ln_ring_tap *tap) const noexcept { ln_ring_tap_close(tap); }
};
using Tap = std::unique_ptr<ln_ring_tap, TapCloser>;

// Opens a tap on `ring` (LN_TAP_EVERY or LN_TAP_NEWEST); "" on success, else libln's text.
inline std::string open_tap(Tap &out, const std::string &ring, uint64_t layout_hash,
                            uint64_t message_size, unsigned mode)
{
    ln_ring_tap *tap = nullptr;
    int rc = ln_ring_tap_open(&tap, ring.c_str(), layout_hash, message_size, mode);
    if (rc != LN_OK)
        return "cannot open ring '" + ring + "': " + ln_last_error();
    out.reset(tap);
    return "";
}

} // namespace lnd::fwd
