#include "cli/snapshot_writer.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/vtk_writer.hpp"
#include "hopper/core/error.hpp"

namespace hopper::cli {
namespace {

namespace fs = std::filesystem;

// A fabricated frame: 3 mobile particles (engine ids 0, 7, 4) and 2 wall particles.
struct Fixture {
    std::vector<int> id{0, 7, 4};
    std::vector<double> x{0.01, -0.02, 0.03}, y{0.10, 0.12, -0.005};
    std::vector<double> vx{0.5, 0.0, -0.25}, vy{-1.0, 0.125, 2.0}, w{3.0, 0.0, -1.5};
    std::vector<double> r{0.00301, 0.00385, 0.00301};
    std::vector<double> wx{-0.05, 0.05}, wy{0.0, 0.0}, wr{0.00385, 0.00385};
    std::vector<double> fn{0.25, 0.0, 1.5}, wfn{0.75, 0.0};

    engine::Snapshot snapshot(double t) const {
        return engine::Snapshot{
            engine::Phase::discharge, t, t - 1.0, id, x, y, vx, vy, w, r, wx, wy, wr, fn, wfn};
    }
};

std::vector<std::string> read_lines(const fs::path& p) {
    std::ifstream in(p);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);)
        lines.push_back(line);
    return lines;
}

std::vector<double> numbers(const std::string& line) {
    std::istringstream is(line);
    std::vector<double> v;
    for (double d; is >> d;)
        v.push_back(d);
    return v;
}

fs::path fresh_dir(const std::string& name) {
    const fs::path dir = fs::path(HOPPER_BINARY_DIR) / "tests" / "cli" / "tmp" / name;
    fs::remove_all(dir);
    return dir;
}

TEST(SnapshotWriter, WritesOneLammpsDumpPerFrame) {
    const Fixture f;
    const fs::path dir = fresh_dir("dump_basic") / "nested";
    // dt = 1e-4 s: the frame at t = 1.25 s is step 12500
    SnapshotWriter writer(dir, 1e-4, {false, true});  // creates the directory with its parents
    ASSERT_TRUE(fs::is_directory(dir));

    const fs::path p0 = writer.write(f.snapshot(1.25));
    EXPECT_EQ(p0, dir / "hopper.000000.dump");
    const auto lines = read_lines(p0);
    ASSERT_EQ(lines.size(), 11u + 5u);  // 11 header lines, 3 mobile + 2 wall
    // LAMMPS's order with `dump_modify time yes`: TIME before TIMESTEP
    EXPECT_EQ(lines[0], "ITEM: TIME");
    EXPECT_DOUBLE_EQ(std::stod(lines[1]), 1.25);
    EXPECT_EQ(lines[2], "ITEM: TIMESTEP");
    EXPECT_EQ(lines[3], "12500");  // the step number, not the frame index
    EXPECT_EQ(lines[4], "ITEM: NUMBER OF ATOMS");
    EXPECT_EQ(lines[5], "5");
    EXPECT_EQ(lines[6], "ITEM: BOX BOUNDS ff ff pp");  // walled in x and y
    EXPECT_EQ(lines[10], "ITEM: ATOMS id type x y z vx vy vz radius omegaz contact_force");

    // Box: every particle inside, padded by the largest diameter; thin slab in z.
    const auto bx = numbers(lines[7]), by = numbers(lines[8]), bz = numbers(lines[9]);
    ASSERT_EQ(bx.size(), 2u);
    ASSERT_EQ(by.size(), 2u);
    ASSERT_EQ(bz.size(), 2u);
    EXPECT_NEAR(bx[0], -0.05 - 0.0077, 1e-12);
    EXPECT_NEAR(bx[1], 0.05 + 0.0077, 1e-12);
    EXPECT_NEAR(by[0], -0.005 - 0.0077, 1e-12);
    EXPECT_NEAR(by[1], 0.12 + 0.0077, 1e-12);
    EXPECT_NEAR(bz[0], -0.00385, 1e-12);
    EXPECT_NEAR(bz[1], 0.00385, 1e-12);

    // Second mobile particle: engine id 7 -> dump id 8, type 1.
    const auto p = numbers(lines[12]);
    ASSERT_EQ(p.size(), 11u);
    const std::vector<double> expected{8, 1, -0.02, 0.12, 0.0, 0.0, 0.125, 0.0, 0.00385, 0.0, 0.0};
    for (std::size_t k = 0; k < expected.size(); ++k)
        EXPECT_NEAR(p[k], expected[k], 1e-9 * (1 + std::abs(expected[k]))) << "column " << k;
    const auto p3 = numbers(lines[13]);
    EXPECT_EQ(p3[0], 5);
    EXPECT_DOUBLE_EQ(p3[9], -1.5);  // omegaz
    EXPECT_DOUBLE_EQ(p3[10], 1.5);  // contact_force (N), for OVITO as for ParaView
    EXPECT_DOUBLE_EQ(numbers(lines[11])[10], 0.25);

    // Walls: type 2, ids above every possible mobile id, zero velocity.
    const auto w0 = numbers(lines[14]), w1 = numbers(lines[15]);
    EXPECT_EQ(w0[0], wall_id_base + 1);
    EXPECT_EQ(w1[0], wall_id_base + 2);
    EXPECT_EQ(w0[1], 2);
    EXPECT_DOUBLE_EQ(w1[2], 0.05);
    EXPECT_EQ(w1[5], 0.0);
    EXPECT_DOUBLE_EQ(w1[8], 0.00385);
    EXPECT_DOUBLE_EQ(w0[10], 0.75);  // the walls' contact forces
    EXPECT_EQ(w1[10], 0.0);

    const fs::path p1 = writer.write(f.snapshot(1.30));
    EXPECT_EQ(p1, dir / "hopper.000001.dump");
    EXPECT_EQ(read_lines(p1)[3], "13000");
    EXPECT_FALSE(fs::exists(dir / "hopper.000000.vtu"));  // only the format asked for
    EXPECT_EQ(writer.frames_written(), 2);
}

TEST(SnapshotWriter, BoxOnlyGrows) {
    Fixture f;
    const fs::path dir = fresh_dir("dump_box");
    SnapshotWriter writer(dir, 1e-4, {false, true});
    writer.write(f.snapshot(0.0));
    f.x = {0.0, 0.0, 0.0};  // everything moves inwards and down
    f.y = {-0.2, -0.2, -0.2};
    const auto lines = read_lines(writer.write(f.snapshot(0.05)));
    const auto by = numbers(lines[8]);
    EXPECT_NEAR(by[0], -0.2 - 0.0077, 1e-12);
    EXPECT_NEAR(by[1], 0.12 + 0.0077, 1e-12);  // kept from the first frame
}

TEST(SnapshotWriter, ReplacesStaleFramesOnly) {
    const fs::path dir = fresh_dir("dump_stale");
    fs::create_directories(dir);
    std::ofstream(dir / "hopper.000123.dump") << "old\n";
    std::ofstream(dir / "notes.txt") << "keep\n";
    std::ofstream(dir / "hopper.final.dump") << "keep\n";
    std::ofstream(dir / "hopper.000007.vtu") << "old\n";
    std::ofstream(dir / "hopper.pvd") << "old\n";
    SnapshotWriter writer(dir, 1e-4);
    EXPECT_FALSE(fs::exists(dir / "hopper.000123.dump"));
    EXPECT_FALSE(fs::exists(dir / "hopper.000007.vtu"));
    EXPECT_FALSE(fs::exists(dir / "hopper.pvd"));
    EXPECT_TRUE(fs::exists(dir / "notes.txt"));
    EXPECT_TRUE(fs::exists(dir / "hopper.final.dump"));
}

TEST(SnapshotWriter, RejectsInconsistentColumnsAndCollidingIds) {
    Fixture f;
    std::ostringstream os;
    DumpBox box;
    f.vx.pop_back();
    EXPECT_THROW(write_dump(os, f.snapshot(0.0), 0, box), std::invalid_argument);
    Fixture g;
    g.id[1] = static_cast<int>(wall_id_base);
    EXPECT_THROW(write_dump(os, g.snapshot(0.0), 0, box), std::invalid_argument);
    Fixture h;
    h.id[0] = -1;
    EXPECT_THROW(write_dump(os, h.snapshot(0.0), 0, box), std::invalid_argument);
}

TEST(SnapshotWriter, FailsClearlyWhenTheDirectoryIsAFile) {
    const fs::path dir = fresh_dir("dump_file");
    fs::create_directories(dir.parent_path());
    std::ofstream(dir) << "a file\n";
    EXPECT_ANY_THROW((SnapshotWriter{dir, 1e-4}));
}

TEST(SnapshotWriter, WritesVtuFramesAndTheirSeries) {
    const Fixture f;
    const fs::path dir = fresh_dir("vtu_basic");
    SnapshotWriter writer(dir, 1e-4, {true, false, true});  // vtu-ascii
    EXPECT_EQ(writer.write(f.snapshot(1.25)), dir / "hopper.000000.vtu");
    writer.write(f.snapshot(1.30));
    EXPECT_FALSE(fs::exists(dir / "hopper.000000.dump"));
    std::ifstream in(dir / "hopper.000000.vtu");
    const std::string vtu((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(vtu.find("NumberOfPoints=\"5\" NumberOfCells=\"5\""), std::string::npos) << vtu;
    for (const char* name : {"\"id\"", "\"type\"", "\"radius\"", "\"velocity\"",
                             "\"angular_velocity\"", "\"TIME\"", "\"TIMESTEP\""})
        EXPECT_NE(vtu.find(name), std::string::npos) << name;
    // ids as the dump's: engine id + 1, walls from wall_id_base + 1
    EXPECT_NE(vtu.find("1 8 5 1000000001 1000000002"), std::string::npos) << vtu;
    EXPECT_NE(vtu.find("12500"), std::string::npos);  // TIMESTEP
    // velocity of the second particle (0, 0.125, 0) and its omega
    EXPECT_NE(vtu.find("0.5 -1 0 0 0.125 0 -0.25 2 0 0 0 0 0 0 0"), std::string::npos) << vtu;
    // contact forces: mobile particles, then walls
    const auto cf = vtu.find("\"contact_force\"");
    ASSERT_NE(cf, std::string::npos) << vtu;
    EXPECT_NE(vtu.find("0.25 0 1.5 0.75 0", cf), std::string::npos) << vtu;
    const auto pvd = read_lines(dir / "hopper.pvd");
    std::string all;
    for (const auto& l : pvd)
        all += l + "\n";
    EXPECT_NE(all.find("timestep=\"1.25\" part=\"0\" file=\"hopper.000000.vtu\""),
              std::string::npos)
        << all;
    EXPECT_NE(all.find("timestep=\"1.3\" part=\"0\" file=\"hopper.000001.vtu\""), std::string::npos)
        << all;
}

// Base64 (RFC 4648, with padding) back to bytes.
std::vector<unsigned char> unbase64(const std::string& text) {
    const std::string table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::vector<unsigned char> out;
    unsigned v = 0;
    int bits = 0;
    for (char c : text) {
        if (c == '=') break;
        const auto k = table.find(c);
        if (k == std::string::npos) ADD_FAILURE() << "not base64: '" << c << "'";
        v = (v << 6) | static_cast<unsigned>(k);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out.push_back(static_cast<unsigned char>((v >> bits) & 0xff));
        }
    }
    return out;
}

std::size_t b64_length(std::size_t bytes) {
    return (bytes + 2) / 3 * 4;
}

// One binary DataArray of a VTU file as VTK reads it: the UInt64 compression header (blocks,
// block size, last block's size, compressed sizes) in base64, then the zlib blocks in base64.
template <class T>
std::vector<T> binary_array(const std::string& vtu, const std::string& name) {
    const auto at = vtu.find("Name=\"" + name + "\"");
    if (at == std::string::npos) return {};
    const auto tag_end = vtu.find('>', at);
    EXPECT_NE(vtu.substr(at, tag_end - at).find("format=\"binary\""), std::string::npos);
    const auto begin = vtu.find_first_not_of(" \n", tag_end + 1);
    const std::string text = vtu.substr(begin, vtu.find('\n', begin) - begin);
    const auto first = unbase64(text.substr(0, b64_length(24)));
    std::uint64_t head[3];
    std::memcpy(head, first.data(), sizeof head);
    const std::size_t header_bytes = (3 + head[0]) * 8;
    const auto header = unbase64(text.substr(0, b64_length(header_bytes)));
    const auto packed = unbase64(text.substr(b64_length(header_bytes)));
    std::vector<unsigned char> raw;
    std::size_t offset = 0;
    for (std::uint64_t b = 0; b < head[0]; ++b) {
        std::uint64_t csize = 0;
        std::memcpy(&csize, header.data() + 24 + 8 * b, 8);
        uLongf size = static_cast<uLongf>(b + 1 == head[0] && head[2] != 0 ? head[2] : head[1]);
        std::vector<unsigned char> block(size);
        EXPECT_EQ(uncompress(block.data(), &size, packed.data() + offset, csize), Z_OK);
        raw.insert(raw.end(), block.begin(), block.begin() + static_cast<std::ptrdiff_t>(size));
        offset += csize;
    }
    EXPECT_EQ(offset, packed.size()) << name;
    std::vector<T> values(raw.size() / sizeof(T));
    std::memcpy(values.data(), raw.data(), values.size() * sizeof(T));
    return values;
}

TEST(SnapshotWriter, WritesBinaryCompressedVtuByDefault) {
    Fixture f;
    // enough particles for several 32 KiB blocks in the larger arrays
    for (int k = 0; k < 3000; ++k) {
        f.id.push_back(10 + k);
        f.x.push_back(1e-5 * k);
        f.y.push_back(0.2 - 1e-5 * k);
        f.vx.push_back(0.001 * k);
        f.vy.push_back(-0.5);
        f.w.push_back(0.0);
        f.r.push_back(0.00301);
        f.fn.push_back(k % 7 == 0 ? 0.1 * k : 0.0);
    }
    const fs::path dir = fresh_dir("vtu_binary");
    SnapshotWriter writer(dir, 1e-4, {true, false});
    writer.write(f.snapshot(1.25));
    std::ifstream in(dir / "hopper.000000.vtu");
    const std::string vtu((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(vtu.find("compressor=\"vtkZLibDataCompressor\""), std::string::npos);
    EXPECT_EQ(vtu.find("format=\"ascii\""), std::string::npos);
    const std::size_t n = f.id.size() + f.wx.size();
    const auto ids = binary_array<std::int64_t>(vtu, "id");
    ASSERT_EQ(ids.size(), n);
    EXPECT_EQ(ids[1], 8);
    EXPECT_EQ(ids[n - 1], wall_id_base + 2);
    const auto force = binary_array<double>(vtu, "contact_force");
    ASSERT_EQ(force.size(), n);
    for (std::size_t i = 0; i < f.fn.size(); ++i)
        ASSERT_EQ(force[i], f.fn[i]) << i;  // exact bits
    EXPECT_EQ(force[n - 2], 0.75);
    const auto v = binary_array<double>(vtu, "velocity");
    ASSERT_EQ(v.size(), 3 * n);
    for (std::size_t i = 0; i < f.vx.size(); ++i) {
        ASSERT_EQ(v[3 * i], f.vx[i]);
        ASSERT_EQ(v[3 * i + 1], f.vy[i]);
        ASSERT_EQ(v[3 * i + 2], 0.0);
    }
    EXPECT_EQ(binary_array<std::int64_t>(vtu, "TIMESTEP"), std::vector<std::int64_t>{12500});
    EXPECT_EQ(binary_array<double>(vtu, "TIME"), std::vector<double>{1.25});
    EXPECT_EQ(binary_array<std::int32_t>(vtu, "type").back(), 2);
    EXPECT_EQ(binary_array<std::uint8_t>(vtu, "types"), std::vector<std::uint8_t>(n, 1));
    // smaller than the same frame as text
    std::ostringstream ascii;
    write_vtu(ascii, f.snapshot(1.25), 12500, VtuEncoding::ascii);
    EXPECT_LT(vtu.size(), ascii.str().size());
}

TEST(SnapshotWriter, ParsesFormats) {
    EXPECT_TRUE(parse_snapshot_formats("vtu").vtu);
    EXPECT_FALSE(parse_snapshot_formats("vtu").vtu_ascii);
    EXPECT_TRUE(parse_snapshot_formats("dump,vtu-ascii").vtu_ascii);
    EXPECT_TRUE(parse_snapshot_formats("dump,vtu-ascii").vtu);
    EXPECT_THROW(parse_snapshot_formats("vtu,vtu-ascii"), core::ConfigError);
    EXPECT_FALSE(parse_snapshot_formats("vtu").dump);
    EXPECT_TRUE(parse_snapshot_formats("dump,vtu").dump);
    EXPECT_THROW(parse_snapshot_formats("vtk"), core::ConfigError);
    EXPECT_THROW(parse_snapshot_formats("vtu,vtu"), core::ConfigError);
    EXPECT_THROW(parse_snapshot_formats(""), core::ConfigError);
}

}  // namespace
}  // namespace hopper::cli
