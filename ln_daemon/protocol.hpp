// The daemon's wire protocol (docs/daemon.md, "Protocol"): the message and error numbers,
// constants and payload codecs come from python/links_and_nodes/wire/daemon.schema through
// the generated daemon_wire.hpp (namespace lnd::wire); this header gives them the names
// the daemon uses (lnd::proto) and adds what follows from them.
#pragma once

#include <cstddef>
#include <cstdint>

#include "daemon_wire.hpp"
#include "wire_io.hpp"

namespace lnd::proto {

using wire::Err;
using wire::ExitKind;
using wire::Msg;
using wire::Stream;

constexpr uint16_t kVersion = wire::kVersion;
using wire::kHeaderBytes;
using wire::kLengthBytes;
using wire::kMagic;
using wire::kMaxFrame;
using wire::kMaxName;
using wire::kNonceBytes;
using wire::kTagBytes;
static_assert(kMaxString == kMaxFrame, "wire_io.hpp's default string limit is the frame's");

// The longest CLIENT_HELLO (type, request id, magic, version, nonce, instance, proof): before
// the handshake no frame may be longer, so an unauthenticated peer costs a few hundred bytes.
constexpr size_t kMaxHelloFrame =
    kHeaderBytes + sizeof kMagic + 2 + kNonceBytes + 4 + kMaxName + kTagBytes;
static_assert(kMaxHelloFrame == 338);

} // namespace lnd::proto
