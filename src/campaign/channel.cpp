#include "hopper/campaign/channel.hpp"

namespace hopper::campaign {

namespace {
constexpr std::uint32_t message_magic = 0x324D5748;  // "HWM2" (HWM1 had no slot)
}

core::Bytes encode(const Message& m) {
    core::ByteWriter w;
    w.u32(message_magic);
    w.u8(static_cast<std::uint8_t>(m.kind));
    w.i32(m.task);
    w.i32(m.attempt);
    w.i32(m.slot);
    w.f64(m.seconds);
    w.u32(static_cast<std::uint32_t>(m.payload.size()));
    w.raw(m.payload);
    return w.take();
}

Message decode_message(std::span<const std::uint8_t> bytes) {
    core::ByteReader in(bytes, "master/worker message");
    if (in.u32() != message_magic) in.fail("not a master/worker message (bad magic)");
    Message m;
    const std::uint8_t kind = in.u8();
    if (kind < 1 || kind > 9) in.fail("unknown message kind " + std::to_string(kind));
    m.kind = static_cast<MessageKind>(kind);
    m.task = in.i32();
    m.attempt = in.i32();
    m.slot = in.i32();
    if (m.slot < 0) in.fail("negative worker slot " + std::to_string(m.slot));
    m.seconds = in.f64();
    const std::uint32_t n = in.u32();
    const auto p = in.raw(n);
    m.payload.assign(p.begin(), p.end());
    in.expect_end();
    return m;
}

}  // namespace hopper::campaign
