#include "cli/snapshot_writer.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <span>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "cli/vtk_writer.hpp"
#include "hopper/core/error.hpp"

namespace hopper::cli {

namespace {

// 9 significant digits: 1e-10 m resolution at hopper scale, ample for viewing, compact files.
void append_number(std::string& out, double v) {
    std::array<char, 32> buf{};
    const auto res =
        std::to_chars(buf.data(), buf.data() + buf.size(), v, std::chars_format::general, 9);
    out.append(buf.data(), res.ptr);
}

void append_int(std::string& out, std::int64_t v) {
    std::array<char, 24> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    out.append(buf.data(), res.ptr);
}

void check_columns(const engine::Snapshot& s) {
    const std::size_t n = s.id.size();
    const bool mobile_ok = s.x.size() == n && s.y.size() == n && s.vx.size() == n &&
                           s.vy.size() == n && s.omega.size() == n && s.radius.size() == n;
    const bool wall_ok =
        s.wall_y.size() == s.wall_x.size() && s.wall_radius.size() == s.wall_x.size();
    if (!mobile_ok || !wall_ok)
        throw std::invalid_argument("snapshot columns have inconsistent lengths");
}

}  // namespace

void DumpBox::include(const engine::Snapshot& s) {
    check_columns(s);
    double r_max = 0.0;
    for (double r : s.radius)
        r_max = std::max(r_max, r);
    for (double r : s.wall_radius)
        r_max = std::max(r_max, r);
    const double pad = 2.0 * r_max;
    auto grow = [&](double x, double y) {
        if (!std::isfinite(x) || !std::isfinite(y)) return;  // never let one bad value poison it
        if (empty) {
            xlo = xhi = x;
            ylo = yhi = y;
            empty = false;
        }
        xlo = std::min(xlo, x - pad);
        xhi = std::max(xhi, x + pad);
        ylo = std::min(ylo, y - pad);
        yhi = std::max(yhi, y + pad);
    };
    for (std::size_t i = 0; i < s.x.size(); ++i)
        grow(s.x[i], s.y[i]);
    for (std::size_t i = 0; i < s.wall_x.size(); ++i)
        grow(s.wall_x[i], s.wall_y[i]);
    if (empty) return;
    zlo = std::min(zlo, -r_max);
    zhi = std::max(zhi, r_max);
}

void write_dump(std::ostream& os, const engine::Snapshot& s, std::int64_t step,
                const DumpBox& box) {
    check_columns(s);
    const std::size_t n_mobile = s.id.size();
    const std::size_t n_wall = s.wall_x.size();
    for (int id : s.id) {
        if (id < 0 || static_cast<std::int64_t>(id) + 1 > wall_id_base)
            throw std::invalid_argument("snapshot: mobile particle id " + std::to_string(id) +
                                        " outside [0, " + std::to_string(wall_id_base - 1) + ")");
    }
    // A box that cannot be empty, even for an empty frame.
    const DumpBox b = box.empty ? DumpBox{-1e-3, 1e-3, -1e-3, 1e-3, -1e-3, 1e-3, false} : box;

    std::string out;
    out.reserve(256 + (n_mobile + n_wall) * 120);
    out += "ITEM: TIME\n";
    append_number(out, s.sim_time);
    out += "\nITEM: TIMESTEP\n";
    append_int(out, step);
    out += "\nITEM: NUMBER OF ATOMS\n";
    append_int(out, static_cast<std::int64_t>(n_mobile + n_wall));
    out += "\nITEM: BOX BOUNDS ff ff pp\n";
    const std::array<std::array<double, 2>, 3> bounds{
        {{b.xlo, b.xhi}, {b.ylo, b.yhi}, {b.zlo, b.zhi}}};
    for (const auto& lh : bounds) {
        append_number(out, lh[0]);
        out += ' ';
        append_number(out, lh[1]);
        out += '\n';
    }
    out += "ITEM: ATOMS id type x y z vx vy vz radius omegaz contact_force\n";
    auto line = [&](std::int64_t id, int type, double x, double y, double vx, double vy, double r,
                    double w, double f) {
        append_int(out, id);
        out += ' ';
        append_int(out, type);
        for (double v : {x, y, 0.0, vx, vy, 0.0, r, w, f}) {
            out += ' ';
            append_number(out, v);
        }
        out += '\n';
    };
    // |F_n| summed over the contacts (N); 0 where the snapshot carries none
    const auto force = [](std::span<const double> f, std::size_t i) {
        return i < f.size() ? f[i] : 0.0;
    };
    for (std::size_t i = 0; i < n_mobile; ++i)
        line(static_cast<std::int64_t>(s.id[i]) + 1, 1, s.x[i], s.y[i], s.vx[i], s.vy[i],
             s.radius[i], s.omega[i], force(s.contact_force, i));
    for (std::size_t i = 0; i < n_wall; ++i)
        line(wall_id_base + 1 + static_cast<std::int64_t>(i), 2, s.wall_x[i], s.wall_y[i], 0.0, 0.0,
             s.wall_radius[i], 0.0, force(s.wall_contact_force, i));
    os << out;
}

SnapshotFormats parse_snapshot_formats(const std::string& text) {
    SnapshotFormats f{false, false};
    std::size_t begin = 0;
    while (true) {
        const std::size_t comma = text.find(',', begin);
        const std::string one =
            text.substr(begin, comma == std::string::npos ? comma : comma - begin);
        const bool vtu = one == "vtu" || one == "vtu-ascii";
        bool& flag = vtu ? f.vtu : f.dump;
        if ((!vtu && one != "dump") || flag)
            throw core::ConfigError(
                "--snapshot-format: " +
                (vtu || one == "dump"
                     ? (vtu && flag ? std::string("VTU given twice") : "'" + one + "' given twice")
                     : "unknown format '" + one + "'") +
                " in '" + text + "' (allowed: vtu or vtu-ascii, and dump; e.g. vtu,dump)");
        flag = true;
        if (one == "vtu-ascii") f.vtu_ascii = true;
        if (comma == std::string::npos) break;
        begin = comma + 1;
    }
    return f;
}

SnapshotWriter::SnapshotWriter(std::filesystem::path dir, double dt, SnapshotFormats formats)
    : dir_(std::move(dir)), dt_(dt), formats_(formats) {
    namespace fs = std::filesystem;
    if (!(dt_ > 0.0)) throw std::invalid_argument("snapshot writer: dt must be > 0");
    fs::create_directories(dir_);
    if (!fs::is_directory(dir_))
        throw std::runtime_error("snapshot directory " + dir_.string() + " is not a directory");
    static const std::regex frame_name(R"(hopper\.([0-9]+\.(dump|vtu)|pvd))");
    std::vector<fs::path> stale;
    for (const auto& entry : fs::directory_iterator(dir_)) {
        if (entry.is_regular_file() &&
            std::regex_match(entry.path().filename().string(), frame_name))
            stale.push_back(entry.path());
    }
    for (const auto& p : stale)
        fs::remove(p);
}

std::filesystem::path SnapshotWriter::frame_path(const std::filesystem::path& dir,
                                                 std::int64_t frame, const char* extension) {
    char name[64];
    std::snprintf(name, sizeof name, "hopper.%06lld.%s", static_cast<long long>(frame), extension);
    return dir / name;
}

namespace {

template <class Write>
void write_file(const std::filesystem::path& path, Write write) {
    std::ofstream os(path, std::ios::binary | std::ios::trunc);
    if (!os)
        throw std::runtime_error("cannot open snapshot file " + path.string() + " for writing");
    write(os);
    os.close();
    if (!os) throw std::runtime_error("cannot write snapshot file " + path.string());
}

}  // namespace

std::filesystem::path SnapshotWriter::write(const engine::Snapshot& s) {
    box_.include(s);
    // Snapshots are taken between steps, so the time is a whole number of steps up to rounding.
    const auto step = static_cast<std::int64_t>(std::llround(s.sim_time / dt_));
    std::filesystem::path written;
    if (formats_.dump) {
        written = frame_path(dir_, frames_, "dump");
        write_file(written, [&](std::ostream& os) { write_dump(os, s, step, box_); });
    }
    if (formats_.vtu) {
        written = frame_path(dir_, frames_, "vtu");
        write_file(written, [&](std::ostream& os) {
            write_vtu(os, s, step, formats_.vtu_ascii ? VtuEncoding::ascii : VtuEncoding::binary);
        });
        times_.push_back(s.sim_time);
        std::vector<PvdEntry> entries;
        for (std::size_t k = 0; k < times_.size(); ++k)
            entries.push_back(
                {times_[k], frame_path({}, static_cast<std::int64_t>(k), "vtu").string()});
        // The series is rewritten after every frame, so it is complete whenever the run stops.
        write_file(dir_ / "hopper.pvd", [&](std::ostream& os) { write_pvd(os, entries); });
    }
    ++frames_;
    return written;
}

}  // namespace hopper::cli
