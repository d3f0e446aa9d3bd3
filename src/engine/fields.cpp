#include "hopper/engine/fields.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hopper::engine {

std::string to_string(FieldKernel k) {
    return k == FieldKernel::gaussian ? "gaussian" : "cell";
}

std::string_view field_name(Field f) {
    switch (f) {
        case Field::vx:
            return "vx";
        case Field::vy:
            return "vy";
        case Field::speed:
            return "speed";
        case Field::pressure:
            return "pressure";
    }
    return "unknown";
}

std::string_view field_unit(Field f) {
    return f == Field::pressure ? "m g" : "m/s";
}

FieldMoments FieldMoments::zero(const FieldGrid& grid) {
    FieldMoments m;
    m.grid = grid;
    const auto n = static_cast<std::size_t>(grid.size());
    m.windows.assign(n, 0);
    m.weight.assign(n, 0.0);
    for (int f = 0; f < field_count; ++f) {
        m.mean[f].assign(n, 0.0);
        m.m2[f].assign(n, 0.0);
    }
    return m;
}

void FieldMoments::merge(const FieldMoments& o) {
    if (!(grid == o.grid))
        throw std::invalid_argument(
            "cannot merge field moments on different grids (origin, cell size, shape or kernel "
            "differ): the realizations were run with different field settings or geometry");
    for (std::size_t c = 0; c < windows.size(); ++c) {
        const auto na = windows[c], nb = o.windows[c];
        if (nb == 0) continue;
        weight[c] += o.weight[c];
        if (na == 0) {
            windows[c] = nb;
            for (int f = 0; f < field_count; ++f) {
                mean[f][c] = o.mean[f][c];
                m2[f][c] = o.m2[f][c];
            }
            continue;
        }
        // Chan, Golub & LeVeque: n = na + nb, delta = mean_b - mean_a,
        // mean = mean_a + delta nb / n, M2 = M2_a + M2_b + delta^2 na nb / n.
        const double n = double(na + nb);
        for (int f = 0; f < field_count; ++f) {
            const double delta = o.mean[f][c] - mean[f][c];
            mean[f][c] += delta * double(nb) / n;
            m2[f][c] += o.m2[f][c] + delta * delta * double(na) * double(nb) / n;
        }
        windows[c] = na + nb;
    }
    if (o.samples > 0) {
        t_first = samples > 0 ? std::min(t_first, o.t_first) : o.t_first;
        t_last = samples > 0 ? std::max(t_last, o.t_last) : o.t_last;
    }
    total_windows += o.total_windows;
    samples += o.samples;
    if (outline_x.empty()) {
        outline_x = o.outline_x;
        outline_y = o.outline_y;
        wall_diameter = o.wall_diameter;
    }
}

double FieldMoments::fluctuation(Field f, int node) const {
    const auto n = windows[node];
    if (n < 2) return 0.0;
    return std::sqrt(std::max(0.0, m2[int(f)][node] / double(n - 1)));
}

FieldAccumulator::FieldAccumulator(const FieldGrid& grid, double window, double start)
    : out_(FieldMoments::zero(grid)), window_(window), start_(start) {
    if (!(grid.nx > 0 && grid.ny > 0 && grid.cell > 0.0))
        throw std::invalid_argument("FieldAccumulator: empty grid");
    if (!(window > 0.0)) throw std::invalid_argument("FieldAccumulator: window must be > 0");
    if (grid.kernel == FieldKernel::gaussian && !(grid.kernel_width > 0.0))
        throw std::invalid_argument("FieldAccumulator: Gaussian kernel width must be > 0");
    min_weight_ = grid.kernel == FieldKernel::gaussian ? 0.1 : 0.0;
    const auto n = static_cast<std::size_t>(grid.size());
    wsum_.assign(n, 0.0);
    for (auto& s : fsum_)
        s.assign(n, 0.0);
}

void FieldAccumulator::add(int node, double w, const std::array<double, field_count>& f) {
    if (wsum_[node] == 0.0) touched_.push_back(node);
    wsum_[node] += w;
    for (int k = 0; k < field_count; ++k)
        fsum_[k][node] += w * f[k];
}

void FieldAccumulator::sample(double t, std::span<const double> x, std::span<const double> y,
                              std::span<const double> vx, std::span<const double> vy,
                              std::span<const double> pressure) {
    const std::int64_t k = std::int64_t(std::floor((t - start_) / window_));
    if (k != current_) {
        close_window();
        current_ = k;
    }
    if (out_.samples == 0) out_.t_first = t;
    out_.t_last = t;
    ++out_.samples;
    ++window_samples_;
    const FieldGrid& g = out_.grid;
    const double inv_h = 1.0 / g.cell;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double u = (x[i] - g.x0) * inv_h, v = (y[i] - g.y0) * inv_h;
        const std::array<double, field_count> f{vx[i], vy[i], std::hypot(vx[i], vy[i]),
                                                pressure[i]};
        if (g.kernel == FieldKernel::cell) {
            if (!(u >= 0.0 && v >= 0.0 && u < g.nx && v < g.ny)) continue;
            add(int(v) * g.nx + int(u), 1.0, f);
            continue;
        }
        // Gaussian: nodes at cell centres within 3 s.
        const double s = g.kernel_width, reach = 3.0 * s * inv_h;
        const int i0 = std::max(0, int(std::ceil(u - 0.5 - reach)));
        const int i1 = std::min(g.nx - 1, int(std::floor(u - 0.5 + reach)));
        const int j0 = std::max(0, int(std::ceil(v - 0.5 - reach)));
        const int j1 = std::min(g.ny - 1, int(std::floor(v - 0.5 + reach)));
        const double inv_2s2 = 0.5 / (s * s);
        for (int j = j0; j <= j1; ++j) {
            const double dy = y[i] - (g.y0 + (j + 0.5) * g.cell);
            for (int ii = i0; ii <= i1; ++ii) {
                const double dx = x[i] - (g.x0 + (ii + 0.5) * g.cell);
                const double r2 = dx * dx + dy * dy;
                if (r2 > 9.0 * s * s) continue;
                add(j * g.nx + ii, std::exp(-r2 * inv_2s2), f);
            }
        }
    }
}

void FieldAccumulator::close_window() {
    if (window_samples_ == 0) return;
    const double threshold = min_weight_ * window_samples_;
    for (int c : touched_) {
        const double w = wsum_[c];
        if (w > 0.0 && w >= threshold) {
            // Welford update with this window's value.
            const auto n = ++out_.windows[c];
            out_.weight[c] += w;
            for (int k = 0; k < field_count; ++k) {
                const double value = fsum_[k][c] / w;
                const double delta = value - out_.mean[k][c];
                out_.mean[k][c] += delta / double(n);
                out_.m2[k][c] += delta * (value - out_.mean[k][c]);
            }
        }
        wsum_[c] = 0.0;
        for (auto& s : fsum_)
            s[c] = 0.0;
    }
    touched_.clear();
    ++out_.total_windows;
    window_samples_ = 0;
}

}  // namespace hopper::engine
