#pragma once
// The checksums the store uses and the versioned encoding of an engine::RealizationResult, on
// the byte writer and reader of core/bytes.hpp. The same bytes travel from
// a worker to the master and sit in the store's journal, so a result is encoded exactly once.
//
// Decoding is checked: a truncated buffer, a count larger than the bytes left, trailing bytes,
// an unknown version or an out-of-range enum throw core::StoreError naming what was being read.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hopper/core/bytes.hpp"
#include "hopper/engine/result.hpp"

namespace hopper::store {

using core::Bytes;
using core::ByteWriter;

// core::ByteReader whose failures are core::StoreError (a damaged journal record or checkpoint
// file is a store that cannot be read).
class ByteReader : public core::ByteReader {
  public:
    using core::ByteReader::ByteReader;

  protected:
    [[noreturn]] void raise(const std::string& message) const override;
};

// CRC-32C (Castagnoli, reflected polynomial 0x82F63B78), as used by iSCSI and ext4;
// crc32c("123456789") == 0xE3069283. `crc` continues a previous checksum.
std::uint32_t crc32c(std::span<const std::uint8_t> data, std::uint32_t crc = 0);

// FNV-1a 64-bit hash (not cryptographic: it identifies texts that are also compared directly).
std::uint64_t fnv1a64(std::string_view text, std::uint64_t h = 0xcbf29ce484222325ull);
std::string hex64(std::uint64_t v);  // 16 lowercase hex digits

// The encoding of a RealizationResult: u32 magic "HRR1", u16 version, then every member of
// RealizationResult in declaration order (Diagnostics, then the fields).
//   Version 1: no fields. A result without fields is still written as version 1, byte for byte
//              as before fields existed, so stores without fields are unchanged and readable by
//              older builds.
//   Version 2: version 1 followed by the fields (engine::FieldMoments): the grid (x0, y0, cell,
//              nx, ny, kernel, kernel_width), total_windows, samples, t_first, t_last, the
//              per-node arrays (windows, weight, mean and M2 of each field; nx * ny each), the
//              outline (x, y) and the wall diameter. Written only when fields are present.
//   Version 3 (issue 13): version 1, then u8 has_fields and the fields as in version 2 when it
//              is 1, then the avalanche sizes (i32s, one per survival interval) and the arches
//              (u32 count, one per jam; each: ids i32s, x f64s, y f64s, span f64, max_angle
//              f64). Written whenever a result has avalanche sizes or arches (every result of
//              this build that opened the outlet); versions 1 and 2 decode with none.
//   Version 4 (issue 12): version 3 with the force path (a string) at the end of the
//              diagnostics. Written whenever a result has one (every result of this build);
//              versions 1 to 3 decode with none.
//   Version 5 and later: the previous version, then the members whose `since` is that version,
//              in the description's order (engine/result.hpp), framed by their types as above.
//              A result is written with the version engine::result_version gives (the newest
//              member it holds), so adding a member changes no earlier result's bytes.
// Every version up to result_codec_version is read. Decoding the fields checks them before
// allocating: nx, ny positive, nx * ny at most max_field_nodes and within the bytes left, every
// per-node array nx * ny long, every number finite, counts non-negative; otherwise
// core::StoreError.
inline constexpr std::uint16_t result_codec_version = engine::result_format_version;  // 4
inline constexpr std::uint16_t result_codec_version_science = 3;
inline constexpr std::uint16_t result_codec_version_fields = 2;
inline constexpr std::uint16_t result_codec_version_without_fields = 1;
inline constexpr std::int64_t max_field_nodes = 20'000'000;  // the engine refuses larger grids
Bytes encode_result(const engine::RealizationResult& r);
void encode_result(ByteWriter& w, const engine::RealizationResult& r);
engine::RealizationResult decode_result(std::span<const std::uint8_t> bytes,
                                        const std::string& what = "realization result");
engine::RealizationResult decode_result(ByteReader& r);

// The result with its wall-clock measurements (diagnostics.wall_seconds, ns_per_particle_step,
// seconds_*) set to zero: two runs of the same realization give equal values, whatever rank or
// machine ran them.
engine::RealizationResult without_wall_clock(engine::RealizationResult r);
// Hash of encode_result(without_wall_clock(r)): equal for bit-identical physics.
std::uint64_t physics_digest(const engine::RealizationResult& r);

}  // namespace hopper::store
