#include "cli/vtk_writer.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "cli/snapshot_writer.hpp"

namespace hopper::cli {

namespace {

static_assert(std::endian::native == std::endian::little,
              "the binary VTU arrays are written as the machine's bytes, declared little-endian");

// Shortest round-trip text: the viewer sees exactly the simulated numbers.
void number(std::string& out, double v) {
    std::array<char, 32> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    out.append(buf.data(), res.ptr);
    out += ' ';
}

template <class Int>
void integer(std::string& out, Int v) {
    std::array<char, 24> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    out.append(buf.data(), res.ptr);
    out += ' ';
}

void base64(std::string& out, const unsigned char* data, std::size_t n) {
    static constexpr char table[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::size_t i = 0;
    for (; i + 3 <= n; i += 3) {
        const unsigned v = (unsigned(data[i]) << 16) | (unsigned(data[i + 1]) << 8) | data[i + 2];
        for (int k = 3; k >= 0; --k)
            out += table[(v >> (6 * k)) & 63];
    }
    if (i < n) {
        const unsigned v =
            (unsigned(data[i]) << 16) | (i + 1 < n ? unsigned(data[i + 1]) << 8 : 0u);
        out += table[(v >> 18) & 63];
        out += table[(v >> 12) & 63];
        out += i + 1 < n ? table[(v >> 6) & 63] : '=';
        out += '=';
    }
}

constexpr std::size_t block_size = 32768;  // VTK's own default

// `raw` as VTK's compressed inline binary: the UInt64 header (blocks, block size, last partial
// block's size or 0, each block's compressed size) in base64, then the blocks in base64.
void compressed(std::string& out, const std::vector<unsigned char>& raw) {
    const std::size_t blocks = (raw.size() + block_size - 1) / block_size;
    std::vector<std::uint64_t> header{blocks, block_size, raw.size() % block_size};
    std::vector<unsigned char> packed;
    for (std::size_t b = 0; b < blocks; ++b) {
        const std::size_t begin = b * block_size;
        const std::size_t n = std::min(block_size, raw.size() - begin);
        uLongf size = compressBound(static_cast<uLong>(n));
        const std::size_t at = packed.size();
        packed.resize(at + size);
        if (compress2(packed.data() + at, &size, raw.data() + begin, static_cast<uLong>(n),
                      Z_DEFAULT_COMPRESSION) != Z_OK)
            throw std::runtime_error("zlib could not compress a VTU array");
        packed.resize(at + size);
        header.push_back(size);
    }
    base64(out, reinterpret_cast<const unsigned char*>(header.data()),
           header.size() * sizeof(std::uint64_t));
    base64(out, packed.data(), packed.size());
}

template <class T>
constexpr const char* vtk_type() {
    if constexpr (std::is_same_v<T, double>) return "Float64";
    if constexpr (std::is_same_v<T, std::int64_t>) return "Int64";
    if constexpr (std::is_same_v<T, std::int32_t>) return "Int32";
    if constexpr (std::is_same_v<T, std::uint8_t>) return "UInt8";
}

// One DataArray of `values` (components interleaved) in the chosen encoding.
template <class T>
void data_array(std::string& out, VtuEncoding enc, const char* name, int components,
                const std::vector<T>& values) {
    out += "        <DataArray type=\"";
    out += vtk_type<T>();
    out += "\"";
    if (name) {
        out += " Name=\"";
        out += name;
        out += "\"";
    }
    out += " NumberOfComponents=\"" + std::to_string(components) + "\" format=\"";
    if (enc == VtuEncoding::ascii) {
        out += "ascii\">\n";
        for (const T v : values) {
            if constexpr (std::is_same_v<T, double>)
                number(out, v);
            else
                integer(out, static_cast<std::int64_t>(v));
        }
        out += "\n        </DataArray>\n";
        return;
    }
    out += "binary\">\n";
    std::vector<unsigned char> raw(values.size() * sizeof(T));
    if (!raw.empty()) std::memcpy(raw.data(), values.data(), raw.size());
    compressed(out, raw);
    out += "\n        </DataArray>\n";
}

}  // namespace

void write_vtu(std::ostream& os, const engine::Snapshot& s, std::int64_t step, VtuEncoding enc) {
    DumpBox{}.include(s);  // checks the columns' lengths (throws std::invalid_argument)
    const std::size_t nm = s.id.size(), nw = s.wall_x.size(), n = nm + nw;
    // The arrays, mobile particles first, then the walls (3-vectors interleaved, z = 0).
    std::vector<double> points, radius, velocity, omega, force;
    std::vector<std::int64_t> connectivity, offsets, id;
    std::vector<std::int32_t> type;
    points.reserve(3 * n);
    velocity.reserve(3 * n);
    for (std::size_t i = 0; i < nm; ++i) {
        points.insert(points.end(), {s.x[i], s.y[i], 0.0});
        velocity.insert(velocity.end(), {s.vx[i], s.vy[i], 0.0});
        id.push_back(static_cast<std::int64_t>(s.id[i]) + 1);
        radius.push_back(s.radius[i]);
        omega.push_back(s.omega[i]);
        // Sum of |F_n| over each particle's contacts (N); 0 where the snapshot carries none.
        force.push_back(i < s.contact_force.size() ? s.contact_force[i] : 0.0);
    }
    for (std::size_t i = 0; i < nw; ++i) {
        points.insert(points.end(), {s.wall_x[i], s.wall_y[i], 0.0});
        velocity.insert(velocity.end(), {0.0, 0.0, 0.0});
        id.push_back(wall_id_base + 1 + static_cast<std::int64_t>(i));
        radius.push_back(s.wall_radius[i]);
        omega.push_back(0.0);
        force.push_back(i < s.wall_contact_force.size() ? s.wall_contact_force[i] : 0.0);
    }
    for (std::size_t i = 0; i < n; ++i) {
        connectivity.push_back(static_cast<std::int64_t>(i));
        offsets.push_back(static_cast<std::int64_t>(i + 1));
        type.push_back(i < nm ? 1 : 2);
    }
    const std::vector<std::uint8_t> cell_types(n, 1);  // VTK_VERTEX

    std::string out;
    out.reserve(512 + n * (enc == VtuEncoding::ascii ? 160 : 100));
    out +=
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
        "byte_order=\"LittleEndian\" header_type=\"UInt64\"";
    if (enc == VtuEncoding::binary) out += " compressor=\"vtkZLibDataCompressor\"";
    out += ">\n  <UnstructuredGrid>\n    <FieldData>\n";
    data_array(out, enc, "TIME", 1, std::vector<double>{s.sim_time});
    data_array(out, enc, "TIMESTEP", 1, std::vector<std::int64_t>{step});
    out += "    </FieldData>\n    <Piece NumberOfPoints=\"" + std::to_string(n) +
           "\" NumberOfCells=\"" + std::to_string(n) + "\">\n      <Points>\n";
    data_array(out, enc, nullptr, 3, points);
    out += "      </Points>\n      <Cells>\n";
    data_array(out, enc, "connectivity", 1, connectivity);
    data_array(out, enc, "offsets", 1, offsets);
    data_array(out, enc, "types", 1, cell_types);
    out += "      </Cells>\n      <PointData Scalars=\"radius\" Vectors=\"velocity\">\n";
    data_array(out, enc, "id", 1, id);
    data_array(out, enc, "type", 1, type);
    data_array(out, enc, "radius", 1, radius);
    data_array(out, enc, "velocity", 3, velocity);
    data_array(out, enc, "angular_velocity", 1, omega);
    data_array(out, enc, "contact_force", 1, force);
    out += "      </PointData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
    os << out;
}

void write_pvd(std::ostream& os, const std::vector<PvdEntry>& frames) {
    std::string out =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\">\n"
        "  <Collection>\n";
    for (const auto& f : frames) {
        out += "    <DataSet timestep=\"";
        std::array<char, 32> buf{};
        const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), f.time);
        out.append(buf.data(), res.ptr);
        out += "\" part=\"0\" file=\"" + f.file + "\"/>\n";
    }
    out += "  </Collection>\n</VTKFile>\n";
    os << out;
}

}  // namespace hopper::cli
