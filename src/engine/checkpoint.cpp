#include "hopper/engine/checkpoint.hpp"

#include <cmath>
#include <string>

#include "hopper/core/error.hpp"
#include "hopper/engine/fields.hpp"
#include "hopper/engine/result.hpp"
#include "hopper/engine/system.hpp"

namespace hopper::engine {

void StateReader::fail() {
    throw core::ConfigError(
        "the checkpoint is truncated or damaged (its state ends early or holds impossible sizes)");
}

namespace {

void put_vec2(StateWriter& w, const Vec2& v) {
    w.put(v.x());
    w.put(v.y());
}

Vec2 get_vec2(StateReader& r) {
    const double x = r.get<double>();
    const double y = r.get<double>();
    return {x, y};
}

}  // namespace

void CheckpointAccess::save(const System& s, StateWriter& w) {
    w.put(s.time_);
    w.put<std::uint8_t>(s.ready_);
    w.put<std::uint8_t>(s.need_rebuild_);
    w.put<std::uint8_t>(s.walls_changed_);
    w.put<std::uint8_t>(s.history_saved_);
    w.put<std::uint8_t>(s.history_);
    w.put(s.next_id_);
    for (const auto* c :
         {&s.x_,  &s.y_,  &s.vx_,    &s.vy_,    &s.w_,     &s.fx_,   &s.fy_,   &s.tq_,
          &s.r_,  &s.m_,  &s.inv_m_, &s.inv_I_, &s.x2_,    &s.x3_,   &s.x4_,   &s.y2_,
          &s.y3_, &s.y4_, &s.w2_,    &s.w3_,    &s.w4_,    &s.xref_, &s.yref_, &s.wx_,
          &s.wy_, &s.wr_, &s.pxi_x_, &s.pxi_y_, &s.wxi_x_, &s.wxi_y_})
        w.put_vector(*c);
    for (const auto* c : {&s.id_, &s.wid_, &s.pstart_, &s.pj_, &s.wstart_, &s.wj_, &s.cell_start_,
                          &s.cell_of_, &s.order_, &s.wcell_start_, &s.wcell_items_})
        w.put_vector(*c);
    put_vec2(w, s.wall_offset_ref_);
    put_vec2(w, s.wall_offset_);
    put_vec2(w, s.wall_velocity_);
    w.put(s.cell_size_);
    w.put(s.grid_x0_);
    w.put(s.grid_y0_);
    w.put(s.grid_nx_);
    w.put(s.grid_ny_);
    w.put(s.wcell_size_);
    w.put(s.wgrid_x0_);
    w.put(s.wgrid_y0_);
    w.put(s.wgrid_nx_);
    w.put(s.wgrid_ny_);
    w.put(s.r_max_);
    w.put(s.wr_max_);
    w.put(s.removal_floor_);
    w.put<std::uint64_t>(s.removals_.size());
    for (const Removal& q : s.removals_) {
        w.put(q.id);
        w.put(q.time);
    }
    put_vec2(w, s.wall_force_);
    w.put(s.max_overlap_seen_);
    w.put(s.contacts_);
    w.put(s.rebuilds_);
    // The timings last: test_kernel_paths compares the bytes before them across force paths.
    w.put(s.phase_.forces);
    w.put(s.phase_.integration);
    w.put(s.phase_.neighbors);
}

void CheckpointAccess::restore(System& s, StateReader& r) {
    s.time_ = r.get<double>();
    s.ready_ = r.get<std::uint8_t>() != 0;
    s.ahead_ = false;  // the fused step's look-ahead is not state: recomputed by a step
    s.need_rebuild_ = r.get<std::uint8_t>() != 0;
    s.walls_changed_ = r.get<std::uint8_t>() != 0;
    s.history_saved_ = r.get<std::uint8_t>() != 0;
    const bool history = r.get<std::uint8_t>() != 0;
    if (history != s.history_)
        throw core::ConfigError(
            "the checkpoint was written with another contact law (tangential springs " +
            std::string(history ? "on" : "off") + ", this realization has them " +
            (s.history_ ? "on" : "off") + ")");
    s.next_id_ = r.get<int>();
    for (auto* c : {&s.x_,  &s.y_,  &s.vx_,    &s.vy_,    &s.w_,     &s.fx_,   &s.fy_,   &s.tq_,
                    &s.r_,  &s.m_,  &s.inv_m_, &s.inv_I_, &s.x2_,    &s.x3_,   &s.x4_,   &s.y2_,
                    &s.y3_, &s.y4_, &s.w2_,    &s.w3_,    &s.w4_,    &s.xref_, &s.yref_, &s.wx_,
                    &s.wy_, &s.wr_, &s.pxi_x_, &s.pxi_y_, &s.wxi_x_, &s.wxi_y_})
        r.get_vector(*c);
    for (auto* c : {&s.id_, &s.wid_, &s.pstart_, &s.pj_, &s.wstart_, &s.wj_, &s.cell_start_,
                    &s.cell_of_, &s.order_, &s.wcell_start_, &s.wcell_items_})
        r.get_vector(*c);
    s.wall_offset_ref_ = get_vec2(r);
    s.wall_offset_ = get_vec2(r);
    s.wall_velocity_ = get_vec2(r);
    s.cell_size_ = r.get<double>();
    s.grid_x0_ = r.get<double>();
    s.grid_y0_ = r.get<double>();
    s.grid_nx_ = r.get<int>();
    s.grid_ny_ = r.get<int>();
    s.wcell_size_ = r.get<double>();
    s.wgrid_x0_ = r.get<double>();
    s.wgrid_y0_ = r.get<double>();
    s.wgrid_nx_ = r.get<int>();
    s.wgrid_ny_ = r.get<int>();
    s.r_max_ = r.get<double>();
    s.wr_max_ = r.get<double>();
    s.removal_floor_ = r.get<double>();
    const auto n_removals = r.get<std::uint64_t>();
    if (n_removals > s.x_.size() + (std::uint64_t(1) << 24)) StateReader::fail();
    s.removals_.clear();
    for (std::uint64_t k = 0; k < n_removals; ++k) {
        const int id = r.get<int>();
        const double t = r.get<double>();
        s.removals_.push_back({id, t});
    }
    s.wall_force_ = get_vec2(r);
    s.max_overlap_seen_ = r.get<double>();
    s.contacts_ = r.get<int>();
    s.rebuilds_ = r.get<std::int64_t>();
    s.phase_.forces = r.get<double>();
    s.phase_.integration = r.get<double>();
    s.phase_.neighbors = r.get<double>();
    check_invariants(s);
    // Per-pair constants of the list are derived, not saved: the same bits from the same list.
    if (!s.pstart_.empty() && !s.wstart_.empty()) s.pair_constants();
}

namespace {

// A state whose checksum is right can still be wrong (a bug or a memory error before the write,
// a hand edit): what the next time steps index with or divide by is checked before it is used.
[[noreturn]] void inconsistent(const std::string& what) {
    throw core::ConfigError("the checkpoint's state is inconsistent (" + what +
                            "); it cannot be continued");
}

bool all_finite(const std::vector<double>& v) {
    for (double x : v)
        if (!std::isfinite(x)) return false;
    return true;
}

bool all_positive(const std::vector<double>& v) {
    for (double x : v)
        if (!(x > 0.0) || !std::isfinite(x)) return false;
    return true;
}

// A CSR row index: empty, or rows + 1 non-decreasing offsets from 0 to `entries`.
bool valid_starts(const std::vector<int>& start, std::size_t rows, std::size_t entries) {
    if (start.empty()) return true;
    if (start.size() != rows + 1 || start.front() != 0 || std::size_t(start.back()) != entries)
        return false;
    for (std::size_t k = 0; k + 1 < start.size(); ++k)
        if (start[k] > start[k + 1]) return false;
    return true;
}

}  // namespace

void CheckpointAccess::check_invariants(const System& s) {
    const std::size_t n = s.x_.size(), nw = s.wx_.size();
    // Columns of one particle kind agree in length.
    for (const auto* c :
         {&s.y_, &s.vx_, &s.vy_, &s.w_, &s.fx_, &s.fy_, &s.tq_, &s.r_, &s.m_, &s.inv_m_, &s.inv_I_})
        if (c->size() != n) inconsistent("particle columns of different lengths");
    if (s.id_.size() != n) inconsistent("particle ids and columns of different lengths");
    if (s.wy_.size() != nw || s.wr_.size() != nw || s.wid_.size() != nw)
        inconsistent("wall columns of different lengths");
    for (const auto* c : {&s.x2_, &s.x3_, &s.x4_, &s.y2_, &s.y3_, &s.y4_, &s.w2_, &s.w3_, &s.w4_})
        if ((!c->empty() || (s.ready_ && s.config_.scheme == Scheme::gear4)) && c->size() != n)
            inconsistent("integrator history of another length than the particle columns");
    if (s.ready_ && (s.xref_.size() != n || s.yref_.size() != n))
        inconsistent("reference positions of another length than the particle columns");
    // Finite values; sizes, masses and inertias positive.
    for (const auto* c :
         {&s.x_,    &s.y_,  &s.vx_, &s.vy_,    &s.w_,     &s.fx_,    &s.fy_,   &s.tq_, &s.x2_,
          &s.x3_,   &s.x4_, &s.y2_, &s.y3_,    &s.y4_,    &s.w2_,    &s.w3_,   &s.w4_, &s.xref_,
          &s.yref_, &s.wx_, &s.wy_, &s.pxi_x_, &s.pxi_y_, &s.wxi_x_, &s.wxi_y_})
        if (!all_finite(*c)) inconsistent("a non-finite position, velocity, force or spring");
    for (const auto* c : {&s.r_, &s.m_, &s.inv_m_, &s.inv_I_, &s.wr_})
        if (!all_positive(*c)) inconsistent("a radius, mass or inertia that is not positive");
    for (double v :
         {s.time_, s.cell_size_, s.grid_x0_, s.grid_y0_, s.wcell_size_, s.wgrid_x0_, s.wgrid_y0_,
          s.r_max_, s.wr_max_, s.wall_offset_ref_.x(), s.wall_offset_ref_.y(), s.wall_offset_.x(),
          s.wall_offset_.y(), s.wall_velocity_.x(), s.wall_velocity_.y()})
        if (!std::isfinite(v)) inconsistent("a non-finite time, grid or wall motion");
    if (std::isnan(s.removal_floor_)) inconsistent("a removal floor that is not a number");
    // Ids: below the next id to hand out.
    if (s.next_id_ < 0) inconsistent("a negative next id");
    for (const auto* c : {&s.id_, &s.wid_})
        for (int id : *c)
            if (id < 0 || id >= s.next_id_) inconsistent("a particle id out of range");
    for (const Removal& q : s.removals_)
        if (q.id < 0 || q.id >= s.next_id_ || !std::isfinite(q.time))
            inconsistent("a removed particle's id out of range");
    // The neighbour list: row starts in order and inside the list; partners inside the columns
    // and, for the half list, later in cell order (the batched force pass relies on it).
    if (!valid_starts(s.pstart_, n, s.pj_.size()) || !valid_starts(s.wstart_, n, s.wj_.size()))
        inconsistent("a neighbour list row start out of order or out of range");
    if (s.pstart_.empty() != s.wstart_.empty() || (s.ready_ && s.pstart_.empty()))
        inconsistent("a neighbour list missing");
    if (s.pstart_.empty() && !(s.pj_.empty() && s.wj_.empty()))
        inconsistent("neighbour list entries without row starts");
    if (!s.pstart_.empty())
        for (std::size_t i = 0; i < n; ++i)
            for (int k = s.pstart_[i]; k < s.pstart_[i + 1]; ++k)
                if (s.pj_[k] <= int(i) || std::size_t(s.pj_[k]) >= n)
                    inconsistent("a neighbour list partner out of range");
    for (int j : s.wj_)
        if (j < 0 || std::size_t(j) >= nw) inconsistent("a wall partner out of range");
    if (s.history_ && !s.pstart_.empty() &&
        (s.pxi_x_.size() != s.pj_.size() || s.pxi_y_.size() != s.pj_.size() ||
         s.wxi_x_.size() != s.wj_.size() || s.wxi_y_.size() != s.wj_.size()))
        inconsistent("tangential springs of another length than the neighbour list");
    // Springs are carried across a rebuild inside it (System::save_history), never between
    // steps: a state cannot hold them half way.
    if (s.history_saved_) inconsistent("springs saved for a rebuild that has not run");
    // The wall grid, used until the walls change.
    if (!s.walls_changed_ && nw > 0) {
        const std::int64_t cells = std::int64_t(s.wgrid_nx_) * std::int64_t(s.wgrid_ny_);
        if (s.wgrid_nx_ < 1 || s.wgrid_ny_ < 1 || !(s.wcell_size_ > 0.0) ||
            cells > (std::int64_t(1) << 31) - 2 ||
            !valid_starts(s.wcell_start_, std::size_t(cells), s.wcell_items_.size()) ||
            s.wcell_start_.empty() || s.wcell_items_.size() != nw)
            inconsistent("a wall grid of impossible size");
        for (int j : s.wcell_items_)
            if (j < 0 || std::size_t(j) >= nw) inconsistent("a wall grid item out of range");
    }
}

void save_moments(const FieldMoments& m, StateWriter& w) {
    w.put(m.grid.x0);
    w.put(m.grid.y0);
    w.put(m.grid.cell);
    w.put(m.grid.nx);
    w.put(m.grid.ny);
    w.put<std::uint8_t>(m.grid.kernel == FieldKernel::gaussian);
    w.put(m.grid.kernel_width);
    w.put_vector(m.windows);
    w.put_vector(m.weight);
    for (int f = 0; f < field_count; ++f) {
        w.put_vector(m.mean[f]);
        w.put_vector(m.m2[f]);
    }
    w.put(m.total_windows);
    w.put(m.samples);
    w.put(m.t_first);
    w.put(m.t_last);
    w.put_vector(m.outline_x);
    w.put_vector(m.outline_y);
    w.put(m.wall_diameter);
}

void restore_moments(FieldMoments& m, StateReader& r) {
    m.grid.x0 = r.get<double>();
    m.grid.y0 = r.get<double>();
    m.grid.cell = r.get<double>();
    m.grid.nx = r.get<int>();
    m.grid.ny = r.get<int>();
    m.grid.kernel = r.get<std::uint8_t>() ? FieldKernel::gaussian : FieldKernel::cell;
    m.grid.kernel_width = r.get<double>();
    r.get_vector(m.windows);
    r.get_vector(m.weight);
    for (int f = 0; f < field_count; ++f) {
        r.get_vector(m.mean[f]);
        r.get_vector(m.m2[f]);
    }
    m.total_windows = r.get<std::int64_t>();
    m.samples = r.get<std::int64_t>();
    m.t_first = r.get<double>();
    m.t_last = r.get<double>();
    r.get_vector(m.outline_x);
    r.get_vector(m.outline_y);
    m.wall_diameter = r.get<double>();
    // Per-node vectors sized by the grid (merge and the store index them by node).
    if (m.grid.nx < 0 || m.grid.ny < 0 ||
        std::int64_t(m.grid.nx) * std::int64_t(m.grid.ny) > (std::int64_t(1) << 31) - 1)
        StateReader::fail();
    const auto nodes = std::size_t(m.grid.size());
    bool sized = m.windows.size() == nodes && m.weight.size() == nodes;
    for (int f = 0; f < field_count; ++f)
        sized = sized && m.mean[f].size() == nodes && m.m2[f].size() == nodes;
    if (!sized) StateReader::fail();
}

void CheckpointAccess::save(const FieldAccumulator& a, StateWriter& w) {
    save_moments(a.out_, w);
    w.put(a.window_);
    w.put(a.start_);
    w.put(a.current_);
    w.put(a.window_samples_);
    w.put(a.min_weight_);
    w.put_vector(a.wsum_);
    for (int f = 0; f < field_count; ++f)
        w.put_vector(a.fsum_[f]);
    w.put_vector(a.touched_);
}

void CheckpointAccess::restore(FieldAccumulator& a, StateReader& r) {
    restore_moments(a.out_, r);
    a.window_ = r.get<double>();
    a.start_ = r.get<double>();
    a.current_ = r.get<std::int64_t>();
    a.window_samples_ = r.get<int>();
    a.min_weight_ = r.get<double>();
    r.get_vector(a.wsum_);
    for (int f = 0; f < field_count; ++f)
        r.get_vector(a.fsum_[f]);
    r.get_vector(a.touched_);
    const auto nodes = std::size_t(a.out_.grid.size());
    if (a.wsum_.size() != nodes) StateReader::fail();
    for (int f = 0; f < field_count; ++f)
        if (a.fsum_[f].size() != nodes) StateReader::fail();
    for (int k : a.touched_)
        if (k < 0 || std::size_t(k) >= nodes) StateReader::fail();
}

void save_result(const RealizationResult& res, StateWriter& w) {
    w.put(static_cast<std::int32_t>(res.status));
    w.put_string(res.message);
    w.put(res.seed);
    w.put(res.particles);
    w.put(res.wall_particles);
    w.put_vector(res.survival_times);
    w.put_vector(res.censored);
    w.put_vector(res.jam_onsets);
    w.put_vector(res.shakes_per_jam);
    w.put(res.n_jams);
    w.put(res.n_shakes);
    w.put(res.n_jams_multi_shake);
    w.put<std::uint8_t>(res.empty_time.has_value());
    w.put(res.empty_time.value_or(0.0));
    w.put<std::uint8_t>(res.discharge_rate.has_value());
    w.put(res.discharge_rate.value_or(0.0));
    w.put(res.discharge_rate_mass);
    w.put(res.discharged);
    w.put_vector(res.exit_times);
    w.put_vector(res.curve_time);
    w.put_vector(res.curve_count);
    w.put<std::uint64_t>(res.events.size());
    for (const Event& e : res.events) {
        w.put(static_cast<std::int32_t>(e.kind));
        w.put(e.time);
        w.put(e.sim_time);
        w.put(e.in_hopper);
    }
    w.put(static_cast<const DiagnosticNumbers&>(res.diagnostics));  // plain numbers
    w.put<std::uint8_t>(res.fields.has_value());
    if (res.fields) save_moments(*res.fields, w);
    // Issue 13: avalanche sizes and arches so far.
    w.put_vector(res.avalanche_sizes);
    w.put<std::uint64_t>(res.arches.size());
    for (const Arch& a : res.arches) {
        w.put_vector(a.ids);
        w.put_vector(a.x);
        w.put_vector(a.y);
        w.put(a.span);
        w.put(a.max_angle);
    }
}

void restore_result(RealizationResult& res, StateReader& r) {
    const auto status = r.get<std::int32_t>();
    if (status < 0 || status > static_cast<std::int32_t>(Status::failed)) StateReader::fail();
    res.status = static_cast<Status>(status);
    res.message = r.get_string();
    res.seed = r.get<std::uint64_t>();
    res.particles = r.get<int>();
    res.wall_particles = r.get<int>();
    r.get_vector(res.survival_times);
    r.get_vector(res.censored);
    r.get_vector(res.jam_onsets);
    r.get_vector(res.shakes_per_jam);
    res.n_jams = r.get<int>();
    res.n_shakes = r.get<int>();
    res.n_jams_multi_shake = r.get<int>();
    const bool has_empty = r.get<std::uint8_t>() != 0;
    const double empty = r.get<double>();
    res.empty_time = has_empty ? std::optional<double>(empty) : std::nullopt;
    const bool has_rate = r.get<std::uint8_t>() != 0;
    const double rate = r.get<double>();
    res.discharge_rate = has_rate ? std::optional<double>(rate) : std::nullopt;
    res.discharge_rate_mass = r.get<double>();
    res.discharged = r.get<int>();
    r.get_vector(res.exit_times);
    r.get_vector(res.curve_time);
    r.get_vector(res.curve_count);
    const auto n_events = r.get<std::uint64_t>();
    if (n_events > (std::uint64_t(1) << 32)) StateReader::fail();
    res.events.clear();
    for (std::uint64_t k = 0; k < n_events; ++k) {
        Event e{};
        const auto kind = r.get<std::int32_t>();
        if (kind < 0 || kind > static_cast<std::int32_t>(Event::Kind::stop)) StateReader::fail();
        e.kind = static_cast<Event::Kind>(kind);
        e.time = r.get<double>();
        e.sim_time = r.get<double>();
        e.in_hopper = r.get<int>();
        res.events.push_back(e);
    }
    static_cast<DiagnosticNumbers&>(res.diagnostics) = r.get<DiagnosticNumbers>();
    if (r.get<std::uint8_t>()) {
        FieldMoments m;
        restore_moments(m, r);
        res.fields = std::move(m);
    } else {
        res.fields.reset();
    }
    r.get_vector(res.avalanche_sizes);
    const auto n_arches = r.get<std::uint64_t>();
    if (n_arches > res.jam_onsets.size()) StateReader::fail();
    res.arches.assign(n_arches, Arch{});
    for (Arch& a : res.arches) {
        r.get_vector(a.ids);
        r.get_vector(a.x);
        r.get_vector(a.y);
        a.span = r.get<double>();
        a.max_angle = r.get<double>();
        if (a.x.size() != a.ids.size() || a.y.size() != a.ids.size()) StateReader::fail();
    }
}

}  // namespace hopper::engine
