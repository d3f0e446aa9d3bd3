// The System's neighbour list: cell grids, the order of particles by cell, the Verlet list of
// pairs with their per-entry constants, removal below the floor, and the springs' history carried
// across a rebuild (system.hpp).
#include <algorithm>
#include <cmath>
#include <span>

#include "columns.hpp"
#include "hopper/engine/system.hpp"

namespace hopper::engine {

namespace {

// The bounding box of non-empty point columns.
struct Box {
    double x0, x1, y0, y1;
};
Box bounds(std::span<const double> xs, std::span<const double> ys) {
    Box b{xs[0], xs[0], ys[0], ys[0]};
    for (std::size_t k = 0; k < xs.size(); ++k) {
        b.x0 = std::min(b.x0, xs[k]);
        b.x1 = std::max(b.x1, xs[k]);
        b.y0 = std::min(b.y0, ys[k]);
        b.y1 = std::max(b.y1, ys[k]);
    }
    return b;
}

// Counting sort of points into an nx x ny grid of cells of size cs with origin (x0, y0);
// points outside are clamped into the border cells (which keeps a neighbour search correct).
// Afterwards the points of cell c are items[start[c]] .. items[start[c + 1] - 1], in input
// order, and cell_of[k] is the cell of point k.
void bin_points(std::span<const double> xs, std::span<const double> ys, double x0, double y0,
                double cs, int nx, int ny, std::vector<int>& start, std::vector<int>& items,
                std::vector<int>& cell_of) {
    const std::size_t n = xs.size();
    const int ncell = nx * ny;
    cell_of.resize(n);
    start.assign(ncell + 1, 0);
    for (std::size_t k = 0; k < n; ++k) {
        const int cx = std::clamp(int((xs[k] - x0) / cs), 0, nx - 1);
        const int cy = std::clamp(int((ys[k] - y0) / cs), 0, ny - 1);
        cell_of[k] = cx + cy * nx;
        ++start[cell_of[k] + 1];
    }
    for (int c = 0; c < ncell; ++c)
        start[c + 1] += start[c];
    items.resize(n);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < n; ++k)
        items[fill[cell_of[k]]++] = int(k);
}

}  // namespace

void System::rebuild() {
    if (!history_saved_) save_history();
    history_saved_ = false;
    remove_below_floor();
    r_max_ = 0.0;
    for (double r : r_)
        r_max_ = std::max(r_max_, r);
    wr_max_ = 0.0;
    for (double r : wr_)
        wr_max_ = std::max(wr_max_, r);
    const double cutoff = 2.0 * r_max_ + config_.skin;
    const double wcutoff = r_max_ + wr_max_ + config_.skin;
    if (walls_changed_ || wcutoff > wcell_size_) build_wall_grid(wcutoff);
    permute_by_cell(cutoff);
    build_pairs();
    restore_history();
    xref_ = x_;
    yref_ = y_;
    wall_offset_ref_ = wall_offset_;
    need_rebuild_ = false;
    ++rebuilds_;
}

void System::remove_below_floor() {
    std::vector<int>& keep = iscratch_;
    keep.clear();
    const auto discarded = [&](int id) {
        return std::find(discard_.begin(), discard_.end(), id) != discard_.end();
    };
    for (std::size_t i = 0; i < y_.size(); ++i) {
        if (y_[i] < removal_floor_)
            removals_.push_back({id_[i], time_});
        else if (discard_.empty() || !discarded(id_[i]))
            keep.push_back(int(i));
    }
    if (keep.size() == y_.size()) return;
    for (auto* col : {&x_,  &y_,  &vx_, &vy_, &w_,  &fx_, &fy_, &tq_, &r_,  &m_,   &inv_m_, &inv_I_,
                      &x2_, &x3_, &x4_, &y2_, &y3_, &y4_, &w2_, &w3_, &w4_, &avx_, &avy_,   &aw_})
        detail::compact(*col, keep);
    detail::compact(id_, keep);
}

void System::build_wall_grid(double cutoff) {
    const std::size_t nw = wx_.size();
    wcell_size_ = cutoff;
    if (nw == 0) {
        wgrid_nx_ = wgrid_ny_ = 1;
        wgrid_x0_ = wgrid_y0_ = 0.0;
        wcell_start_.assign(2, 0);
        wcell_items_.clear();
        walls_changed_ = false;
        return;
    }
    const auto [x0, x1, y0, y1] = bounds(wx_, wy_);
    wgrid_x0_ = x0 - cutoff;
    wgrid_y0_ = y0 - cutoff;
    wgrid_nx_ = std::max(1, int(std::ceil((x1 - x0 + 2 * cutoff) / cutoff)));
    wgrid_ny_ = std::max(1, int(std::ceil((y1 - y0 + 2 * cutoff) / cutoff)));
    std::vector<int> cell;
    bin_points(wx_, wy_, wgrid_x0_, wgrid_y0_, cutoff, wgrid_nx_, wgrid_ny_, wcell_start_,
               wcell_items_, cell);
    walls_changed_ = false;
}

void System::permute_by_cell(double cutoff) {
    const std::size_t n = x_.size();
    if (n == 0) {
        cell_start_.assign(2, 0);
        grid_nx_ = grid_ny_ = 1;
        return;
    }
    // Grid over the particles and walls; clamping outliers into the border cells keeps the
    // search correct (clamping never separates two cells' neighbours), only slower for them.
    auto [x0, x1, y0, y1] = bounds(x_, y_);
    if (!wx_.empty()) {
        // Keep the grid to the hopper's extent (plus a margin) even if a particle flew away.
        const double m = 4.0 * cutoff;
        const double wx0 = wgrid_x0_ + wall_offset_.x() - m;
        const double wy0 = wgrid_y0_ + wall_offset_.y() - m;
        const double wx1 = wx0 + wgrid_nx_ * wcell_size_ + 2 * m;
        const double wy1 = wy0 + wgrid_ny_ * wcell_size_ + 2 * m;
        x0 = std::max(std::min(x0, wx0 + m), wx0);
        y0 = std::max(std::min(y0, wy0 + m), wy0);
        x1 = std::min(std::max(x1, wx1 - m), wx1);
        y1 = std::min(std::max(y1, wy1 - m), wy1);
    }
    double cs = cutoff;
    const double max_cells = 4.0 * double(n + wx_.size()) + 1024.0;
    while (((x1 - x0) / cs + 1) * ((y1 - y0) / cs + 1) > max_cells)
        cs *= 1.5;
    cell_size_ = cs;
    grid_x0_ = x0;
    grid_y0_ = y0;
    grid_nx_ = std::max(1, int((x1 - x0) / cs) + 1);
    grid_ny_ = std::max(1, int((y1 - y0) / cs) + 1);
    const int ncell = grid_nx_ * grid_ny_;
    // Counting sort: order_[new index] = old index.
    bin_points(x_, y_, x0, y0, cs, grid_nx_, grid_ny_, cell_start_, order_, cell_of_);
    for (auto* col : {&x_,  &y_,  &vx_, &vy_, &w_,  &fx_, &fy_, &tq_, &r_,  &m_,   &inv_m_, &inv_I_,
                      &x2_, &x3_, &x4_, &y2_, &y3_, &y4_, &w2_, &w3_, &w4_, &avx_, &avy_,   &aw_})
        detail::permute(*col, order_, scratch_);
    detail::permute(id_, order_, iscratch_);
    // cell_of_ in the new order is non-decreasing; rebuild it from the starts.
    for (int c = 0; c < ncell; ++c)
        for (int i = cell_start_[c]; i < cell_start_[c + 1]; ++i)
            cell_of_[i] = c;
}

void System::build_pairs() {
    const std::size_t n = x_.size();
    pstart_.resize(n + 1);
    wstart_.resize(n + 1);
    pj_.clear();
    wj_.clear();
    const double skin = config_.skin;
    // Half stencil: own cell (j > i) and four of the eight neighbours, all later in cell order;
    // particles are sorted by cell, so every partner has j > i. The batched force pass relies on
    // it (force_batch.hpp: a particle's own sum is added after every share it receives).
    static constexpr int sx[4] = {1, -1, 0, 1};
    static constexpr int sy[4] = {0, 1, 1, 1};
    for (std::size_t i = 0; i < n; ++i) {
        pstart_[i] = int(pj_.size());
        const double xi = x_[i], yi = y_[i], ri = r_[i];
        const int c = cell_of_[i];
        const int cx = c % grid_nx_, cy = c / grid_nx_;
        auto consider = [&](int j) {
            const double dx = xi - x_[j], dy = yi - y_[j];
            const double cut = ri + r_[j] + skin;
            if (dx * dx + dy * dy < cut * cut) pj_.push_back(j);
        };
        for (int j = int(i) + 1; j < cell_start_[c + 1]; ++j)
            consider(j);
        for (int s = 0; s < 4; ++s) {
            const int nx = cx + sx[s], ny = cy + sy[s];
            if (nx < 0 || nx >= grid_nx_ || ny >= grid_ny_) continue;
            const int nc = nx + ny * grid_nx_;
            for (int j = cell_start_[nc]; j < cell_start_[nc + 1]; ++j)
                consider(j);
        }
    }
    pstart_[n] = int(pj_.size());
    // Mobile-wall pairs from the wall grid (in the walls' base frame).
    const double ox = wall_offset_.x(), oy = wall_offset_.y();
    for (std::size_t i = 0; i < n; ++i) {
        wstart_[i] = int(wj_.size());
        if (wx_.empty()) continue;
        const double qx = x_[i] - ox, qy = y_[i] - oy, ri = r_[i];
        const int cx = std::clamp(int(std::floor((qx - wgrid_x0_) / wcell_size_)), -1, wgrid_nx_);
        const int cy = std::clamp(int(std::floor((qy - wgrid_y0_) / wcell_size_)), -1, wgrid_ny_);
        for (int ny = cy - 1; ny <= cy + 1; ++ny) {
            if (ny < 0 || ny >= wgrid_ny_) continue;
            for (int nx = cx - 1; nx <= cx + 1; ++nx) {
                if (nx < 0 || nx >= wgrid_nx_) continue;
                const int nc = nx + ny * wgrid_nx_;
                for (int k = wcell_start_[nc]; k < wcell_start_[nc + 1]; ++k) {
                    const int j = wcell_items_[k];
                    const double dx = qx - wx_[j], dy = qy - wy_[j];
                    const double cut = ri + wr_[j] + skin;
                    if (dx * dx + dy * dy < cut * cut) wj_.push_back(j);
                }
            }
        }
    }
    wstart_[n] = int(wj_.size());
    pair_constants();
}

void System::pair_constants() {
    const std::size_t n = x_.size();
    pmbar_.resize(pj_.size());
    wmbar_.resize(wj_.size());
    pown_.resize(pj_.size());
    wown_.resize(wj_.size());
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = pstart_[i]; k < pstart_[i + 1]; ++k) {
            pmbar_[k] = 1.0 / (inv_m_[i] + inv_m_[pj_[k]]);
            pown_[k] = int(i);
        }
        for (int k = wstart_[i]; k < wstart_[i + 1]; ++k) {
            wmbar_[k] = 1.0 / inv_m_[i];
            wown_[k] = int(i);
        }
    }
}

// Contact springs survive rebuilds keyed by the persistent ids of the pair: saved grouped by
// owner (the smaller id for two mobile particles, the mobile one against a wall), restored by a
// short scan of the owner's few entries. O(pairs), no sorting, no maps.
void System::save_history() {
    hist_start_.assign(next_id_ + 1, 0);
    hist_partner_.clear();
    hist_x_.clear();
    hist_y_.clear();
    // The list's rows are the particles it was built for: those added since (the steady state's
    // re-insertions) come after them and have no springs yet. Comparing the row count with
    // the grown particle count instead dropped every spring at each re-insertion (round 3).
    if (!history_ || pstart_.empty() || pstart_.size() > x_.size() + 1) return;
    const std::size_t n = pstart_.size() - 1;
    auto each_spring = [&](auto&& fn) {
        for (std::size_t i = 0; i < n; ++i) {
            for (int k = pstart_[i]; k < pstart_[i + 1]; ++k)
                if (pxi_x_[k] != 0.0 || pxi_y_[k] != 0.0) {
                    const int a = id_[i], b = id_[pj_[k]];
                    fn(std::min(a, b), std::max(a, b), pxi_x_[k], pxi_y_[k]);
                }
            for (int k = wstart_[i]; k < wstart_[i + 1]; ++k)
                if (wxi_x_[k] != 0.0 || wxi_y_[k] != 0.0)
                    fn(id_[i], wid_[wj_[k]], wxi_x_[k], wxi_y_[k]);
        }
    };
    each_spring([&](int owner, int, double, double) { ++hist_start_[owner + 1]; });
    for (int k = 0; k < next_id_; ++k)
        hist_start_[k + 1] += hist_start_[k];
    const int total = hist_start_[next_id_];
    hist_partner_.resize(total);
    hist_x_.resize(total);
    hist_y_.resize(total);
    std::vector<int> fill(hist_start_.begin(), hist_start_.end() - 1);
    each_spring([&](int owner, int partner, double sx, double sy) {
        const int at = fill[owner]++;
        hist_partner_[at] = partner;
        hist_x_[at] = sx;
        hist_y_[at] = sy;
    });
}

void System::restore_history() {
    if (!history_) {
        pxi_x_.clear();
        pxi_y_.clear();
        wxi_x_.clear();
        wxi_y_.clear();
        return;
    }
    pxi_x_.assign(pj_.size(), 0.0);
    pxi_y_.assign(pj_.size(), 0.0);
    wxi_x_.assign(wj_.size(), 0.0);
    wxi_y_.assign(wj_.size(), 0.0);
    if (hist_partner_.empty()) return;
    auto lookup = [&](int owner, int partner, double& sx, double& sy) {
        if (owner + 1 >= int(hist_start_.size())) return;
        for (int k = hist_start_[owner]; k < hist_start_[owner + 1]; ++k)
            if (hist_partner_[k] == partner) {
                sx = hist_x_[k];
                sy = hist_y_[k];
                return;
            }
    };
    const std::size_t n = x_.size();
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = pstart_[i]; k < pstart_[i + 1]; ++k) {
            const int a = id_[i], b = id_[pj_[k]];
            lookup(std::min(a, b), std::max(a, b), pxi_x_[k], pxi_y_[k]);
        }
        for (int k = wstart_[i]; k < wstart_[i + 1]; ++k)
            lookup(id_[i], wid_[wj_[k]], wxi_x_[k], wxi_y_[k]);
    }
}

}  // namespace hopper::engine
