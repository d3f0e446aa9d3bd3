#pragma once
// Particle snapshots as LAMMPS-style text dump files, one file per frame, which OVITO and ParaView
// open without conversion (`campaign simulate ... --snapshots DIR`).
//
// Files: DIR/hopper.<frame>.dump with the frame index zero-padded to 6 digits (000000, 000001,
// ...). Any hopper.<digits>.dump already in DIR is removed when the writer starts, so a directory
// never mixes frames of two runs. Each file holds one frame:
//
//   ITEM: TIMESTEP
//   <frame index>
//   ITEM: TIME
//   <simulated time since the fill, s>
//   ITEM: NUMBER OF ATOMS
//   <mobile + wall particles>
//   ITEM: BOX BOUNDS pp pp pp
//   xlo xhi
//   ylo yhi
//   zlo zhi
//   ITEM: ATOMS id type x y z vx vy vz radius omegaz
//   <one line per particle: mobile particles first, then wall particles>
//
// Units SI: metres, m/s, rad/s. The 2D scene lies in the plane z = 0; the box is the bounding box
// of every particle written so far (it only grows, so an animation's view stays put), padded by
// one largest diameter in x and y, and a slab of +-(largest radius) in z. The "pp" flags are
// nominal: the hopper is not periodic, and the padding keeps any periodic image beyond contact
// range.
//   - Mobile particles: type 1, id = engine id + 1 (LAMMPS ids are positive).
//   - Wall particles: type 2, id = wall_id_base + 1 + index in the frame's wall list. The engine's
//     ids of wall particles are not in the snapshot, so walls are numbered from 1'000'000'001 on,
//     far above any mobile id. Wall velocities and omegaz are written as 0 (the snapshot has none;
//     walls move only while the hopper is shaken).
// ITEM: TIME is what LAMMPS writes with `dump_modify time yes`; OVITO reads it as the frame's
// "Time" attribute.

#include <cstdint>
#include <filesystem>
#include <ostream>

#include "hopper/engine/realization.hpp"

namespace hopper::cli {

// Axis-aligned bounds of the dump box (metres).
struct DumpBox {
    double xlo = 0, xhi = 0, ylo = 0, yhi = 0, zlo = 0, zhi = 0;
    bool empty = true;
    // Grows the box to contain the particles of `s` (padded as described above).
    void include(const engine::Snapshot& s);
};

inline constexpr std::int64_t wall_id_base = 1'000'000'000;

// Writes one frame in the format above. Throws std::invalid_argument when the snapshot's columns
// have inconsistent lengths or a mobile id would collide with the wall ids.
void write_dump(std::ostream& os, const engine::Snapshot& s, std::int64_t frame,
                const DumpBox& box);

class SnapshotWriter {
  public:
    // Creates `dir` (with parents) if needed and removes stale hopper.<digits>.dump files.
    // Throws std::filesystem::filesystem_error or std::runtime_error with the path on failure.
    explicit SnapshotWriter(std::filesystem::path dir);

    // Writes the next frame; returns its path. Throws std::runtime_error when the file cannot be
    // written.
    std::filesystem::path write(const engine::Snapshot& s);

    std::int64_t frames_written() const { return frames_; }
    const std::filesystem::path& directory() const { return dir_; }

    static std::filesystem::path frame_path(const std::filesystem::path& dir, std::int64_t frame);

  private:
    std::filesystem::path dir_;
    DumpBox box_;
    std::int64_t frames_ = 0;
};

}  // namespace hopper::cli
