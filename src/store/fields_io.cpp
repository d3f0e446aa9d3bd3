// The coarse-grained fields of a store file: /fields/<row>, one group per realization that has
// them (docs/store.md, "The HDF5 file"), written and read back.

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "hopper/core/error.hpp"
#include "schema.hpp"

namespace hopper::store::layout {

namespace {

std::string field_text(int f) {
    return std::string(engine::field_name(static_cast<engine::Field>(f)));
}

std::string field_units(int f) {
    return std::string(engine::field_unit(static_cast<engine::Field>(f)));
}

// "fields.window_s" -> its value in a point's scene text ("name=value" lines); absent when the
// line is missing or not a finite number ("unset").
std::optional<double> scene_value(const std::string& scene, const std::string& name) {
    const std::string key = name + "=";
    std::size_t at = 0;
    while (at < scene.size()) {
        const std::size_t end = std::min(scene.find('\n', at), scene.size());
        if (scene.compare(at, key.size(), key) == 0) {
            const std::string v = scene.substr(at + key.size(), end - at - key.size());
            char* stop = nullptr;
            const double x = std::strtod(v.c_str(), &stop);
            if (v.empty() || stop != v.c_str() + v.size() || !std::isfinite(x)) return std::nullopt;
            return x;
        }
        at = end + 1;
    }
    return std::nullopt;
}

template <class T>
std::vector<T> read_array(const h5::Id& g, const std::string& name, h5::hid mem_type,
                          const std::vector<h5::hsize>& dims, const std::string& where) {
    h5::Id ds = h5::open_dataset(g, name);
    if (h5::dims_of(ds) != dims)
        throw core::StoreError(where + "/" + name + " does not have the grid's shape");
    h5::hsize n = 1;
    for (h5::hsize d : dims)
        n *= d;
    std::vector<T> v(static_cast<std::size_t>(n));
    h5::read_array(ds, mem_type, v.data(), where + "/" + name);
    return v;
}

}  // namespace

void write_fields(const h5::Id& parent, const std::string& scene, int point, std::int64_t row,
                  int realization, const engine::FieldMoments& m) {
    const h5::hid i64 = h5::mem_type(h5::Scalar::i64), f64 = h5::mem_type(h5::Scalar::f64);
    const std::string name = std::to_string(row);
    if (h5::exists(parent, name))  // left by an interrupted write: replace it
        h5::remove(parent, name, "cannot replace /fields/" + name);
    h5::Id g = h5::create_group(parent, name);
    const engine::FieldGrid& grid = m.grid;
    describe(g, "",
             "coarse-grained fields of /realizations row " + name +
                 ": per grid node (ny x nx, row j = y0 + (j + 1/2) cell, column i = x0 + (i + "
                 "1/2) cell) the windows it took part in, the summed weight, and per field the "
                 "mean and M2 (sum of squared deviations) over those windows; lengths in m, "
                 "times in s of discharge time");
    h5::set_attr(g, "row", static_cast<std::int64_t>(row));
    h5::set_attr(g, "point", static_cast<std::int64_t>(point));
    h5::set_attr(g, "realization", static_cast<std::int64_t>(realization));
    h5::set_attr(g, "x0", fin(grid.x0));
    h5::set_attr(g, "y0", fin(grid.y0));
    h5::set_attr(g, "cell", fin(grid.cell));
    h5::set_attr(g, "nx", static_cast<std::int64_t>(grid.nx));
    h5::set_attr(g, "ny", static_cast<std::int64_t>(grid.ny));
    h5::set_attr(g, "kernel", engine::to_string(grid.kernel));
    h5::set_attr(g, "kernel_width", fin(grid.kernel_width));
    for (const char* key : {"window_s", "sample_interval_s", "start_s", "end_s"})
        if (const auto v = scene_value(scene, std::string("fields.") + key))
            h5::set_attr(g, key, *v);
    h5::set_attr(g, "samples", m.samples);
    h5::set_attr(g, "total_windows", m.total_windows);
    h5::set_attr(g, "t_first", fin(m.t_first));
    h5::set_attr(g, "t_last", fin(m.t_last));
    h5::set_attr(g, "wall_diameter", fin(m.wall_diameter));

    const std::vector<h5::hsize> dims = {static_cast<h5::hsize>(std::max(grid.ny, 0)),
                                         static_cast<h5::hsize>(std::max(grid.nx, 0))};
    const std::size_t nodes = static_cast<std::size_t>(dims[0] * dims[1]);
    auto check_size = [&](std::size_t n, const std::string& what) {
        if (n != nodes)
            throw core::StoreError("the fields of row " + name + ": " + what + " has " +
                                   std::to_string(n) + " values for " + std::to_string(grid.nx) +
                                   " x " + std::to_string(grid.ny) + " nodes");
    };
    check_size(m.windows.size(), "windows");
    h5::Id ds =
        h5::write_array(g, "windows", h5::file_type(h5::Scalar::i64), i64, m.windows.data(), dims);
    describe(ds, "1", "windows in which the node took part (n)");
    auto real = [&](const std::string& ds_name, const std::vector<double>& v,
                    const std::string& units, const std::string& description) {
        check_size(v.size(), ds_name);
        std::vector<double> x(v.size());
        std::transform(v.begin(), v.end(), x.begin(), fin);
        h5::Id d = h5::write_array(g, ds_name, h5::file_type(h5::Scalar::f64), f64, x.data(), dims);
        describe(d, units, description);
    };
    real("weight", m.weight, "1",
         "summed kernel weight over all samples (cell kernel: particle-samples in the cell)");
    for (int f = 0; f < engine::field_count; ++f) {
        const std::string u = field_units(f);
        real(
            "mean_" + field_text(f), m.mean[f], u,
            "mean over windows of the window value of " + field_text(f) + " (0 where windows = 0)");
        real("m2_" + field_text(f), m.m2[f], "(" + u + ")^2",
             "sum over windows of squared deviations from the mean of " + field_text(f) +
                 " (Welford; merge with Chan et al.)");
    }
    const std::size_t k = std::min(m.outline_x.size(), m.outline_y.size());
    std::vector<double> ox(k), oy(k);
    for (std::size_t i = 0; i < k; ++i) {
        ox[i] = fin(m.outline_x[i]);
        oy[i] = fin(m.outline_y[i]);
    }
    const std::vector<h5::hsize> odims = {static_cast<h5::hsize>(k)};
    h5::Id dx =
        h5::write_array(g, "outline_x", h5::file_type(h5::Scalar::f64), f64, ox.data(), odims);
    describe(dx, "m",
             "centre line of the right-hand wall particles from the outlet upwards (mirror x for "
             "the left wall)");
    h5::Id dy =
        h5::write_array(g, "outline_y", h5::file_type(h5::Scalar::f64), f64, oy.data(), odims);
    describe(dy, "m", "y of outline_x");
}

engine::FieldMoments read_fields(const h5::Id& g, const std::string& where) {
    auto need_f64 = [&](const char* name) {
        const auto v = h5::get_f64_attr(g, name);
        if (!v) throw core::StoreError(where + " lacks the attribute " + name);
        return *v;
    };
    auto need_int = [&](const char* name) {
        const auto v = h5::get_int_attr(g, name);
        if (!v) throw core::StoreError(where + " lacks the attribute " + name);
        return *v;
    };
    const h5::hid i64 = h5::mem_type(h5::Scalar::i64), f64 = h5::mem_type(h5::Scalar::f64);
    engine::FieldMoments m;
    engine::FieldGrid& grid = m.grid;
    grid.x0 = need_f64("x0");
    grid.y0 = need_f64("y0");
    grid.cell = need_f64("cell");
    const std::int64_t nx = need_int("nx"), ny = need_int("ny");
    if (nx <= 0 || ny <= 0 || nx > max_field_nodes || ny > max_field_nodes ||
        nx * ny > max_field_nodes)
        throw core::StoreError(where + " has a grid of " + std::to_string(nx) + " x " +
                               std::to_string(ny) + " nodes");
    grid.nx = static_cast<int>(nx);
    grid.ny = static_cast<int>(ny);
    const auto kernel = h5::get_string_attr(g, "kernel");
    if (!kernel || (*kernel != "cell" && *kernel != "gaussian"))
        throw core::StoreError(where + " has no valid kernel attribute");
    grid.kernel = *kernel == "gaussian" ? engine::FieldKernel::gaussian : engine::FieldKernel::cell;
    grid.kernel_width = need_f64("kernel_width");
    m.samples = need_int("samples");
    m.total_windows = need_int("total_windows");
    m.t_first = need_f64("t_first");
    m.t_last = need_f64("t_last");
    m.wall_diameter = need_f64("wall_diameter");
    const std::vector<h5::hsize> dims = {static_cast<h5::hsize>(ny), static_cast<h5::hsize>(nx)};
    m.windows = read_array<std::int64_t>(g, "windows", i64, dims, where);
    m.weight = read_array<double>(g, "weight", f64, dims, where);
    for (int f = 0; f < engine::field_count; ++f) {
        m.mean[f] = read_array<double>(g, "mean_" + field_text(f), f64, dims, where);
        m.m2[f] = read_array<double>(g, "m2_" + field_text(f), f64, dims, where);
    }
    auto outline = [&](const char* name) {
        const auto d = h5::dims_of(h5::open_dataset(g, name));
        if (d.size() != 1) throw core::StoreError(where + "/" + name + " is not 1-D");
        return read_array<double>(g, name, f64, d, where);
    };
    m.outline_x = outline("outline_x");
    m.outline_y = outline("outline_y");
    if (m.outline_x.size() != m.outline_y.size())
        throw core::StoreError(where + ": outline_x and outline_y differ in length");
    return m;
}

}  // namespace hopper::store::layout
