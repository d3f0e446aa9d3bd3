#pragma once
// Particle snapshots as VTK XML files, which ParaView (and VisIt) open natively: one unstructured
// grid per frame (.vtu) and a ParaView collection (.pvd) that lists the frames with their times,
// so ParaView loads the whole series as one time-dependent source.
//
// A frame holds every particle as a point (one VTK_VERTEX cell each, so that every representation
// shows them; "Point Gaussian" with the radius array as its scale draws them as disks) in the
// plane z = 0, SI units, mobile particles first, then the wall particles. Point arrays:
//   id                Int64    mobile: engine id + 1; walls: wall_id_base + 1 + index (as the dump)
//   type              Int32    1 mobile, 2 wall
//   radius            Float64  m
//   velocity          Float64  3 components, m/s (walls 0)
//   angular_velocity  Float64  rad/s about z (walls 0)
//   contact_force     Float64  sum of |F_n| over the particle's contacts, N
// Field data: TIME (s since the fill) and TIMESTEP (the step number), as ParaView's readers
// name them.
//
// Encoding: binary by default -- each array's little-endian bytes compressed with zlib in
// blocks of 32 KiB and written inline in base64 after VTK's UInt64 compression header
// (number of blocks, block size, size of the last partial block, compressed size of each
// block; the header and the blocks each base64-encoded), the format ParaView writes itself with
// compressor="vtkZLibDataCompressor". Exact: the viewer sees the simulated doubles' bits.
// ASCII on request (shortest round-trip text, the same numbers): readable, about 2.2x larger
// (a quickstart frame of 600 disks: 88 kB as text, 39 kB binary).

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "hopper/engine/realization.hpp"

namespace hopper::cli {

enum class VtuEncoding { binary, ascii };

void write_vtu(std::ostream& os, const engine::Snapshot& s, std::int64_t step,
               VtuEncoding encoding = VtuEncoding::binary);

struct PvdEntry {
    double time = 0.0;  // s
    std::string file;   // relative to the .pvd file
};
void write_pvd(std::ostream& os, const std::vector<PvdEntry>& frames);

}  // namespace hopper::cli
