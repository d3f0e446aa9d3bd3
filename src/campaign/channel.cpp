#include "hopper/campaign/channel.hpp"

#include "hopper/core/described.hpp"

namespace hopper::campaign {

namespace {
constexpr std::uint32_t message_magic = 0x324D5748;  // "HWM2" (HWM1 had no slot)

// The wire format, described once (core/described.hpp): the format number, the kind, the
// task, attempt and worker slot, the worker's seconds, the payload.
template <class Io, core::Is<Message> M>
void fields(Io& io, M& m) {
    io.format(message_magic, "master/worker message");
    io.enumeration(m.kind, MessageKind::task, MessageKind::checkpoint_now);
    io(m.task);
    io(m.attempt);
    io(m.slot);
    io.check(m.slot >= 0, [&] { return "negative worker slot " + std::to_string(m.slot); });
    io(m.seconds);
    io.blob(m.payload);
}

}  // namespace

core::Bytes encode(const Message& m) {
    core::ByteWriter w;
    core::Put io(w);
    fields(io, m);
    return w.take();
}

Message decode_message(std::span<const std::uint8_t> bytes) {
    core::ByteReader in(bytes, "master/worker message");
    core::Get io(in);
    Message m;
    fields(io, m);
    in.expect_end();
    return m;
}

}  // namespace hopper::campaign
