// The System's neighbour list: cell grids, the order of particles by cell, the Verlet list of
// pairs with their per-entry constants, removal below the floor, and the springs' history carried
// across a rebuild (system.hpp).
#include <algorithm>
#include <cmath>
#include <span>

#include "columns.hpp"
#include "hopper/engine/system.hpp"
#include "integrate.hpp"

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
    ahead_ = false;  // new order and reference positions: the next step predicts on its own
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
    for (auto* col : particle_columns(*this))
        detail::compact(*col, keep);
    detail::compact(id_, keep);
    if (carry_) detail::compact(carry_old_, keep);  // the springs' old indices follow
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
    for (auto* col : particle_columns(*this))
        detail::permute(*col, order_, scratch_);
    detail::permute(id_, order_, iscratch_);
    if (carry_) detail::permute(carry_old_, order_, iscratch_);  // the springs' old indices
    // cell_of_ in the new order is non-decreasing; rebuild it from the starts.
    for (int c = 0; c < ncell; ++c)
        for (int i = cell_start_[c]; i < cell_start_[c + 1]; ++i)
            cell_of_[i] = c;
}

namespace {

// Appends to `list` (the first `count` entries in use, the rest room) item(k) for every k of
// [lo, hi) with within(item(k)), in order. Each item is written and kept, the count advanced,
// only when it is within: no branch on the data, whose outcome the CPU cannot predict (about
// a third of the candidates of the half stencil are kept). The same list as a push_back per hit.
template <class Item, class Within>
void append_within(std::vector<int>& list, std::size_t& count, int lo, int hi, Item item,
                   Within within) {
    if (hi <= lo) return;
    if (count + std::size_t(hi - lo) > list.size())
        list.resize(std::max(2 * list.size(), count + std::size_t(hi - lo)));
    int* const out = list.data();
    std::size_t c = count;
    for (int k = lo; k < hi; ++k) {
        const int j = item(k);
        out[c] = j;
        c += within(j) ? 1 : 0;
    }
    count = c;
}

}  // namespace

void System::build_pairs() {
    const std::size_t n = x_.size();
    pstart_.resize(n + 1);
    wstart_.resize(n + 1);
    std::size_t np = 0, nw = 0;  // entries of pj_ and wj_ in use; the vectors are sized ahead
    const double skin = config_.skin;
    // Half stencil: own cell (j > i) and four of the eight neighbours, all later in cell order;
    // particles are sorted by cell, so every partner has j > i. The batched force pass relies on
    // it (force_batch.hpp: a particle's own sum is added after every share it receives).
    static constexpr int sx[4] = {1, -1, 0, 1};
    static constexpr int sy[4] = {0, 1, 1, 1};
    for (std::size_t i = 0; i < n; ++i) {
        pstart_[i] = int(np);
        const double xi = x_[i], yi = y_[i], ri = r_[i];
        const int c = cell_of_[i];
        const int cx = c % grid_nx_, cy = c / grid_nx_;
        const auto within = [&](int j) {
            const double dx = xi - x_[j], dy = yi - y_[j];
            const double cut = ri + r_[j] + skin;
            return dx * dx + dy * dy < cut * cut;
        };
        const auto same = [](int j) { return j; };  // particles are listed by index
        append_within(pj_, np, int(i) + 1, cell_start_[c + 1], same, within);
        for (int s = 0; s < 4; ++s) {
            const int nx = cx + sx[s], ny = cy + sy[s];
            if (nx < 0 || nx >= grid_nx_ || ny >= grid_ny_) continue;
            const int nc = nx + ny * grid_nx_;
            append_within(pj_, np, cell_start_[nc], cell_start_[nc + 1], same, within);
        }
    }
    pstart_[n] = int(np);
    pj_.resize(np);
    // Mobile-wall pairs from the wall grid (in the walls' base frame).
    const double ox = wall_offset_.x(), oy = wall_offset_.y();
    for (std::size_t i = 0; i < n; ++i) {
        wstart_[i] = int(nw);
        if (wx_.empty()) continue;
        const double qx = x_[i] - ox, qy = y_[i] - oy, ri = r_[i];
        const int cx = std::clamp(int(std::floor((qx - wgrid_x0_) / wcell_size_)), -1, wgrid_nx_);
        const int cy = std::clamp(int(std::floor((qy - wgrid_y0_) / wcell_size_)), -1, wgrid_ny_);
        const auto wall = [&](int k) { return wcell_items_[k]; };
        const auto within = [&](int j) {
            const double dx = qx - wx_[j], dy = qy - wy_[j];
            const double cut = ri + wr_[j] + skin;
            return dx * dx + dy * dy < cut * cut;
        };
        for (int ny = cy - 1; ny <= cy + 1; ++ny) {
            if (ny < 0 || ny >= wgrid_ny_) continue;
            for (int nx = cx - 1; nx <= cx + 1; ++nx) {
                if (nx < 0 || nx >= wgrid_nx_) continue;
                const int nc = nx + ny * wgrid_nx_;
                append_within(wj_, nw, wcell_start_[nc], wcell_start_[nc + 1], wall, within);
            }
        }
    }
    wstart_[n] = int(nw);
    wj_.resize(nw);
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
    // What each block of the fused passes reads (CorrectArgs::reach, integrate.hpp).
    constexpr int B = detail::block_rows;
    block_reach_.assign((n + B - 1) / B, 0);
    for (std::size_t b = 0; b < block_reach_.size(); ++b) {
        const int i1 = std::min(int(n), int(b + 1) * B);
        int reach = i1;
        for (int k = pstart_[b * B]; k < pstart_[i1]; ++k)
            reach = std::max(reach, pj_[k] + 1);
        block_reach_[b] = reach;
    }
    // R* and the Hertz law's constants per entry (the same expressions as the law's, once per
    // rebuild instead of once per step): only for the laws that read them.
    const bool hertz = config_.normal_law == NormalLaw::hertz;
    const bool rstar = hertz || config_.rolling;
    for (auto* col : {&prstar_, &wrstar_, &phk_, &whk_, &pheta_, &wheta_})
        col->clear();
    if (!rstar) return;
    prstar_.resize(pj_.size());
    wrstar_.resize(wj_.size());
    if (hertz) {
        phk_.resize(pj_.size());
        pheta_.resize(pj_.size());
        whk_.resize(wj_.size());
        wheta_.resize(wj_.size());
    }
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = pstart_[i]; k < pstart_[i + 1]; ++k) {
            prstar_[k] = reduced_radius(r_[i], r_[pj_[k]]);
            if (hertz)
                HertzSpringLaw::pair_constants(config_.particle, prstar_[k], pmbar_[k], phk_[k],
                                               pheta_[k]);
        }
        for (int k = wstart_[i]; k < wstart_[i + 1]; ++k) {
            wrstar_[k] = reduced_radius(r_[i], wr_[wj_[k]]);
            if (hertz)
                HertzSpringLaw::pair_constants(config_.wall, wrstar_[k], wmbar_[k], whk_[k],
                                               wheta_[k]);
        }
    }
}

// Contact springs survive rebuilds (round 3, docs/performance.md, phase 6): the list before the
// rebuild is moved aside whole (no copy), and each entry of the new list finds its pair in the
// old one through the particles' old indices (the compaction's and the cell order's
// permutations composed): a pair of particles was listed in the row of the one earlier in the
// old cell order, a particle-wall pair in the particle's row, so a short scan of one old row
// finds it. O(pairs); no sorting, no maps, nothing sized by the ids ever issued.
void System::save_history() {
    const std::size_t n = x_.size();
    // The list's rows are the particles it was built for; particles added since (the steady
    // state's re-insertions) come after them and have no springs yet (old index -1). Requiring
    // the row count to equal the grown particle count dropped every spring at each
    // re-insertion (fixed on main in 9e7f4f9; test Springs.SurviveTheAdditionOfAParticle).
    const std::size_t rows = pstart_.empty() ? 0 : pstart_.size() - 1;
    carry_ = history_ && !pstart_.empty() && rows <= n && pxi_x_.size() == pj_.size() &&
             wxi_x_.size() == wj_.size();
    if (!carry_) return;
    old_pstart_.swap(pstart_);
    old_pj_.swap(pj_);
    old_wstart_.swap(wstart_);
    old_wj_.swap(wj_);
    const auto ps = pair_springs(*this), ws = wall_springs(*this);
    for (std::size_t c = 0; c < spring_count(); ++c) {
        old_springs_[c].swap(*ps[c]);
        old_wall_springs_[c].swap(*ws[c]);
    }
    carry_old_.resize(n);
    for (std::size_t i = 0; i < n; ++i)
        carry_old_[i] = i < rows ? int(i) : -1;
    wall_old_.clear();
}

void System::restore_history() {
    // The kept columns (spring_count) sized to the new list and zero, the others empty.
    const auto ps = pair_springs(*this), ws = wall_springs(*this);
    const std::size_t nc = spring_count();
    for (std::size_t c = 0; c < ps.size(); ++c) {
        ps[c]->assign(c < nc ? pj_.size() : 0, 0.0);
        ws[c]->assign(c < nc ? wj_.size() : 0, 0.0);
    }
    if (!history_) {
        carry_ = false;
        return;
    }
    if (!carry_) return;
    carry_ = false;
    const int* old = carry_old_.data();
    const std::size_t n = x_.size();
    for (std::size_t i = 0; i < n; ++i) {
        const int a = old[i];
        if (a < 0) continue;  // added since the last list: no springs to carry
        for (int k = pstart_[i]; k < pstart_[i + 1]; ++k) {
            const int b = old[pj_[k]];
            if (b < 0) continue;
            const int lo = std::min(a, b), hi = std::max(a, b);
            for (int m = old_pstart_[lo]; m < old_pstart_[lo + 1]; ++m)
                if (old_pj_[m] == hi) {
                    for (std::size_t c = 0; c < nc; ++c)
                        (*ps[c])[k] = old_springs_[c][m];
                    break;
                }
        }
        for (int k = wstart_[i]; k < wstart_[i + 1]; ++k) {
            const int wb = wall_old_.empty() ? wj_[k] : wall_old_[wj_[k]];
            for (int m = old_wstart_[a]; m < old_wstart_[a + 1]; ++m)
                if (old_wj_[m] == wb) {
                    for (std::size_t c = 0; c < nc; ++c)
                        (*ws[c])[k] = old_wall_springs_[c][m];
                    break;
                }
        }
    }
}

}  // namespace hopper::engine
