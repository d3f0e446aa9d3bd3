#pragma once
// Particle snapshots (`campaign simulate ... --snapshots DIR`), one file per frame, in either or
// both of two formats:
//   vtu        VTK XML unstructured grids DIR/hopper.<frame>.vtu and the series DIR/hopper.pvd,
//              which ParaView opens natively (cli/vtk_writer.hpp), binary and compressed;
//   vtu-ascii  the same with the arrays as text (larger; for reading by eye or by scripts);
//   dump       LAMMPS text dump files DIR/hopper.<frame>.dump (OVITO, LAMMPS tools).
//
// The frame index is zero-padded to 6 digits (000000, 000001, ...). Any hopper.<digits>.dump,
// hopper.<digits>.vtu and hopper.pvd already in DIR are removed when the writer starts, so a
// directory never mixes frames of two runs. A dump file holds one frame, as LAMMPS writes it with
// `dump_modify time yes`:
//
//   ITEM: TIME
//   <simulated time since the fill, s>
//   ITEM: TIMESTEP
//   <the step number: simulated time / dt, rounded>
//   ITEM: NUMBER OF ATOMS
//   <mobile + wall particles>
//   ITEM: BOX BOUNDS ff ff pp
//   xlo xhi
//   ylo yhi
//   zlo zhi
//   ITEM: ATOMS id type x y z vx vy vz radius omegaz contact_force
//   <one line per particle: mobile particles first, then wall particles>
//
// Units SI: metres, m/s, rad/s. The 2D scene lies in the plane z = 0; the box is the bounding box
// of every particle written so far (it only grows, so an animation's view stays put), padded by
// one largest diameter in x and y, and a slab of +-(largest radius) in z. x and y are fixed
// boundaries ("ff": the hopper has walls); z is nominally periodic ("pp"), the usual way of
// writing a 2D system.
//   - Mobile particles: type 1, id = engine id + 1 (LAMMPS ids are positive).
//   - Wall particles: type 2, id = wall_id_base + 1 + index in the frame's wall list. The engine's
//     ids of wall particles are not in the snapshot, so walls are numbered from 1'000'000'001 on,
//     far above any mobile id. Wall velocities and omegaz are written as 0 (the snapshot has none;
//     walls move only while the hopper is shaken).
//   - contact_force: the sum of |F_n| over the particle's contacts (N), as in the VTU frames; OVITO
//     maps it to a particle property of that name (colour coding, histograms).
// OVITO reads ITEM: TIME as the frame's "Time" attribute.

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

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
void write_dump(std::ostream& os, const engine::Snapshot& s, std::int64_t step, const DumpBox& box);

struct SnapshotFormats {
    bool vtu = true;
    bool dump = true;
    bool vtu_ascii = false;  // the VTU arrays as text (vtu-ascii), not compressed binary
};
// A comma-separated list of "vtu" or "vtu-ascii" and "dump" (either order; default vtu,dump).
// Throws core::ConfigError naming the bad entry.
SnapshotFormats parse_snapshot_formats(const std::string& text);

class SnapshotWriter {
  public:
    // Creates `dir` (with parents) if needed and removes stale frames. `dt` (s) turns a
    // snapshot's simulated time into its step number. Throws std::filesystem::filesystem_error or
    // std::runtime_error with the path on failure.
    SnapshotWriter(std::filesystem::path dir, double dt, SnapshotFormats formats = {});

    // Writes the next frame; returns its path (the .vtu file when that format is on, else the
    // .dump file). Throws std::runtime_error when the file cannot be
    // written.
    std::filesystem::path write(const engine::Snapshot& s);

    std::int64_t frames_written() const { return frames_; }
    const std::filesystem::path& directory() const { return dir_; }

    // The frame's file of the given extension ("dump", "vtu").
    static std::filesystem::path frame_path(const std::filesystem::path& dir, std::int64_t frame,
                                            const char* extension = "dump");

  private:
    std::filesystem::path dir_;
    double dt_;
    SnapshotFormats formats_;
    DumpBox box_;
    std::int64_t frames_ = 0;
    std::vector<double> times_;  // of the frames written (the .pvd lists them all)
};

}  // namespace hopper::cli
