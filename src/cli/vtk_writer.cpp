#include "cli/vtk_writer.hpp"

#include <array>
#include <charconv>

#include "cli/snapshot_writer.hpp"

namespace hopper::cli {

namespace {

// Shortest round-trip text: the viewer sees exactly the simulated numbers.
void number(std::string& out, double v) {
    std::array<char, 32> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    out.append(buf.data(), res.ptr);
    out += ' ';
}

void integer(std::string& out, std::int64_t v) {
    std::array<char, 24> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    out.append(buf.data(), res.ptr);
    out += ' ';
}

// An ASCII DataArray whose values `emit` appends.
template <class Emit>
void data_array(std::string& out, const char* type, const char* name, int components, Emit emit) {
    out += "        <DataArray type=\"";
    out += type;
    out += "\"";
    if (name) {
        out += " Name=\"";
        out += name;
        out += "\"";
    }
    out += " NumberOfComponents=\"" + std::to_string(components) + "\" format=\"ascii\">\n";
    emit();
    out += "\n        </DataArray>\n";
}

}  // namespace

void write_vtu(std::ostream& os, const engine::Snapshot& s, std::int64_t step) {
    DumpBox{}.include(s);  // checks the columns' lengths (throws std::invalid_argument)
    const std::size_t nm = s.id.size(), nw = s.wall_x.size(), n = nm + nw;
    std::string out;
    out.reserve(512 + n * 160);
    out +=
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
        "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n"
        "    <FieldData>\n";
    data_array(out, "Float64", "TIME", 1, [&] { number(out, s.sim_time); });
    data_array(out, "Int64", "TIMESTEP", 1, [&] { integer(out, step); });
    out += "    </FieldData>\n    <Piece NumberOfPoints=\"" + std::to_string(n) +
           "\" NumberOfCells=\"" + std::to_string(n) + "\">\n      <Points>\n";
    data_array(out, "Float64", nullptr, 3, [&] {
        for (std::size_t i = 0; i < nm; ++i) {
            number(out, s.x[i]);
            number(out, s.y[i]);
            out += "0 ";
        }
        for (std::size_t i = 0; i < nw; ++i) {
            number(out, s.wall_x[i]);
            number(out, s.wall_y[i]);
            out += "0 ";
        }
    });
    out += "      </Points>\n      <Cells>\n";
    data_array(out, "Int64", "connectivity", 1, [&] {
        for (std::size_t i = 0; i < n; ++i)
            integer(out, static_cast<std::int64_t>(i));
    });
    data_array(out, "Int64", "offsets", 1, [&] {
        for (std::size_t i = 0; i < n; ++i)
            integer(out, static_cast<std::int64_t>(i + 1));
    });
    data_array(out, "UInt8", "types", 1, [&] {
        for (std::size_t i = 0; i < n; ++i)
            out += "1 ";  // VTK_VERTEX
    });
    out += "      </Cells>\n      <PointData Scalars=\"radius\" Vectors=\"velocity\">\n";
    data_array(out, "Int64", "id", 1, [&] {
        for (int id : s.id)
            integer(out, static_cast<std::int64_t>(id) + 1);
        for (std::size_t i = 0; i < nw; ++i)
            integer(out, wall_id_base + 1 + static_cast<std::int64_t>(i));
    });
    data_array(out, "Int32", "type", 1, [&] {
        for (std::size_t i = 0; i < n; ++i)
            out += i < nm ? "1 " : "2 ";
    });
    data_array(out, "Float64", "radius", 1, [&] {
        for (double r : s.radius)
            number(out, r);
        for (double r : s.wall_radius)
            number(out, r);
    });
    data_array(out, "Float64", "velocity", 3, [&] {
        for (std::size_t i = 0; i < nm; ++i) {
            number(out, s.vx[i]);
            number(out, s.vy[i]);
            out += "0 ";
        }
        for (std::size_t i = 0; i < nw; ++i)
            out += "0 0 0 ";
    });
    data_array(out, "Float64", "angular_velocity", 1, [&] {
        for (double w : s.omega)
            number(out, w);
        for (std::size_t i = 0; i < nw; ++i)
            out += "0 ";
    });
    // Sum of |F_n| over each particle's contacts (N); 0 where the snapshot carries none.
    data_array(out, "Float64", "contact_force", 1, [&] {
        for (std::size_t i = 0; i < nm; ++i)
            number(out, i < s.contact_force.size() ? s.contact_force[i] : 0.0);
        for (std::size_t i = 0; i < nw; ++i)
            number(out, i < s.wall_contact_force.size() ? s.wall_contact_force[i] : 0.0);
    });
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
