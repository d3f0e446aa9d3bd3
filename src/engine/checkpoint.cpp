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

// The System's state, described once: every column, the neighbour list with its springs, the
// grids, the wall motion, the removals and the counters.
template <class Io, class S>
void CheckpointAccess::system(Io& io, S& s) {
    const auto vec2 = [&](auto& v) {
        io(v.x());
        io(v.y());
    };
    io(s.time_);
    io(s.ready_);
    io(s.need_rebuild_);
    io(s.walls_changed_);
    io(s.history_saved_);
    io.template as<std::uint8_t>(
        s.history_, [](bool h) { return h; },
        [&](std::uint8_t h) {
            if (bool(h) != s.history_)
                throw core::ConfigError(
                    "the checkpoint was written with another contact law (tangential springs " +
                    std::string(h ? "on" : "off") + ", this realization has them " +
                    (s.history_ ? "on" : "off") + ")");
            return s.history_;
        });
    io(s.next_id_);
    for (auto* c : System::saved_columns(s))
        io(*c);
    for (auto* c :
         {&s.xref_, &s.yref_, &s.wx_, &s.wy_, &s.wr_, &s.pxi_x_, &s.pxi_y_, &s.wxi_x_, &s.wxi_y_})
        io(*c);
    // The rolling springs (issue 39), only in the states of a law that has them: a state of any
    // other law has the bytes it had before (format 2). Which law a state was written with is
    // fixed by the scene its fingerprint names (material.rolling_law).
    if (s.rolling_history_)
        for (auto* c : {&s.pxi_r_, &s.wxi_r_})
            io(*c);
    for (auto* c : {&s.id_, &s.wid_, &s.pstart_, &s.pj_, &s.wstart_, &s.wj_, &s.cell_start_,
                    &s.cell_of_, &s.order_, &s.wcell_start_, &s.wcell_items_})
        io(*c);
    vec2(s.wall_offset_ref_);
    vec2(s.wall_offset_);
    vec2(s.wall_velocity_);
    io(s.cell_size_);
    io(s.grid_x0_);
    io(s.grid_y0_);
    io(s.grid_nx_);
    io(s.grid_ny_);
    io(s.wcell_size_);
    io(s.wgrid_x0_);
    io(s.wgrid_y0_);
    io(s.wgrid_nx_);
    io(s.wgrid_ny_);
    io(s.r_max_);
    io(s.wr_max_);
    io(s.removal_floor_);
    io.list(s.removals_, 12, [&](auto& q) {
        io(q.id);
        io(q.time);
    });
    io.check([&] { return s.removals_.size() <= s.x_.size() + (std::size_t(1) << 24); });
    vec2(s.wall_force_);
    io(s.max_overlap_seen_);
    io(s.contacts_);
    io(s.rebuilds_);
    // The timings last: test_kernel_paths compares the bytes before them across force paths.
    io(s.phase_.forces);
    io(s.phase_.integration);
    io(s.phase_.neighbors);
}

void CheckpointAccess::save(const System& s, StateWriter& w) {
    StatePut io(w);
    system(io, s);
}

void CheckpointAccess::restore(System& s, StateReader& r) {
    StateGet io(r);
    system(io, s);
    s.ahead_ = false;  // the fused step's look-ahead is not state: recomputed by a step
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
    for (const auto* c : System::history_columns(s))
        if ((!c->empty() || (s.ready_ && s.config_.scheme == Scheme::gear4)) && c->size() != n)
            inconsistent("integrator history of another length than the particle columns");
    if (s.ready_ && (s.xref_.size() != n || s.yref_.size() != n))
        inconsistent("reference positions of another length than the particle columns");
    // Finite values; sizes, masses and inertias positive.
    for (const auto* c : {&s.x_,     &s.y_,     &s.vx_,    &s.vy_,    &s.w_,     &s.fx_,   &s.fy_,
                          &s.tq_,    &s.x2_,    &s.x3_,    &s.x4_,    &s.y2_,    &s.y3_,   &s.y4_,
                          &s.w2_,    &s.w3_,    &s.w4_,    &s.xref_,  &s.yref_,  &s.wx_,   &s.wy_,
                          &s.pxi_x_, &s.pxi_y_, &s.wxi_x_, &s.wxi_y_, &s.pxi_r_, &s.wxi_r_})
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
    if (!s.pstart_.empty()) {
        const auto ps = System::pair_springs(s), ws = System::wall_springs(s);
        for (std::size_t c = 0; c < s.spring_count(); ++c)
            if (ps[c]->size() != s.pj_.size() || ws[c]->size() != s.wj_.size())
                inconsistent("contact springs of another length than the neighbour list");
    }
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

namespace {

template <class R, class T>
concept Is = std::same_as<std::remove_const_t<R>, T>;

// The field moments (a result's, and the accumulator's so far), described once.
template <class Io, Is<FieldMoments> M>
void fields(Io& io, M& m) {
    io(m.grid.x0);
    io(m.grid.y0);
    io(m.grid.cell);
    io(m.grid.nx);
    io(m.grid.ny);
    io.template as<std::uint8_t>(
        m.grid.kernel, [](FieldKernel k) { return k == FieldKernel::gaussian; },
        [](std::uint8_t b) { return b ? FieldKernel::gaussian : FieldKernel::cell; });
    io(m.grid.kernel_width);
    io(m.windows);
    io(m.weight);
    for (int f = 0; f < field_count; ++f) {
        io(m.mean[f]);
        io(m.m2[f]);
    }
    io(m.total_windows);
    io(m.samples);
    io(m.t_first);
    io(m.t_last);
    io(m.outline_x);
    io(m.outline_y);
    io(m.wall_diameter);
    // Per-node vectors sized by the grid (merge and the store index them by node).
    io.check([&] {
        if (m.grid.nx < 0 || m.grid.ny < 0 ||
            std::int64_t(m.grid.nx) * std::int64_t(m.grid.ny) > (std::int64_t(1) << 31) - 1)
            return false;
        const auto nodes = std::size_t(m.grid.size());
        bool sized = m.windows.size() == nodes && m.weight.size() == nodes;
        for (int f = 0; f < field_count; ++f)
            sized = sized && m.mean[f].size() == nodes && m.m2[f].size() == nodes;
        return sized;
    });
}

// One arch in the state format.
template <class Io, Is<Arch> A>
void arch(Io& io, A& a) {
    io(a.ids);
    io(a.x);
    io(a.y);
    io(a.span);
    io(a.max_angle);
    io.check([&] { return a.x.size() == a.ids.size() && a.y.size() == a.ids.size(); });
}

// The result so far in state format 2, kept to read the states written before format 3.
template <class Io, Is<RealizationResult> R>
void result_v2(Io& io, R& res) {
    io.enumeration(res.status, Status::failed);
    io(res.message);
    io(res.seed);
    io(res.particles);
    io(res.wall_particles);
    io(res.survival_times);
    io(res.censored);
    io(res.jam_onsets);
    io(res.shakes_per_jam);
    io(res.n_jams);
    io(res.n_shakes);
    io(res.n_jams_multi_shake);
    io.flagged(res.empty_time);
    io.flagged(res.discharge_rate);
    io(res.discharge_rate_mass);
    io(res.discharged);
    io(res.exit_times);
    io(res.curve_time);
    io(res.curve_count);
    io.list(res.events, 24, [&](auto& e) {
        io.enumeration(e.kind, Event::Kind::stop);
        io(e.time);
        io(e.sim_time);
        io(e.in_hopper);
    });
    // The diagnostics' plain numbers as one block.
    using Numbers =
        std::conditional_t<std::is_const_v<R>, const DiagnosticNumbers, DiagnosticNumbers>;
    io(static_cast<Numbers&>(res.diagnostics));
    io.optional(res.fields, [&](auto& m) { fields(io, m); });
    // Issue 13: avalanche sizes and arches so far.
    io(res.avalanche_sizes);
    io.list(res.arches, 32, [&](auto& a) { arch(io, a); });
    io.check([&] { return res.arches.size() <= res.jam_onsets.size(); });
}

// One member of the result in the state format, chosen by its type: enumerations within their
// range, optionals flagged, events and diagnostics by their own descriptions (result.hpp).
template <class Io, class M>
void member(Io& io, M& v) {
    using T = std::remove_const_t<M>;
    if constexpr (std::is_same_v<T, Status>) {
        io.enumeration(v, Status::failed);
    } else if constexpr (std::is_same_v<T, Event::Kind>) {
        io.enumeration(v, Event::Kind::stop);
    } else if constexpr (std::is_same_v<T, std::optional<double>>) {
        io.flagged(v);
    } else if constexpr (std::is_same_v<T, std::optional<FieldMoments>>) {
        io.optional(v, [&](auto& m) { fields(io, m); });
    } else if constexpr (std::is_same_v<T, std::vector<Event>>) {
        io.list(v, 24, [&](auto& e) {
            for_each_event_field([&](const auto& f) { member(io, e.*f.member); });
        });
    } else if constexpr (std::is_same_v<T, std::vector<Arch>>) {
        io.list(v, 32, [&](auto& a) { arch(io, a); });
    } else if constexpr (std::is_same_v<T, Diagnostics>) {
        for_each_diagnostic([&](const auto& f) { member(io, v.*f.member); });
    } else {
        io(v);
    }
}

// The result so far in state format 3: the result format version of the build that wrote it
// (result_format_version), then every member of the description (result.hpp) up to that
// version, in its order, the wall-clock and unjournaled diagnostics too (a resumed realization
// goes on counting them). A member added to the description later is saved and restored
// without an edit here; in a state written before it, it starts empty (and a per-element array
// that then misses the elements before the state is left out: drop_incomplete_arrays).
template <class Io, Is<RealizationResult> R>
void result_v3(Io& io, R& res, std::uint16_t version) {
    for_each_result_field([&](const auto& f) {
        if (f.since <= version) member(io, res.*f.member);
    });
    io.check([&] { return res.arches.size() <= res.jam_onsets.size(); });
}

}  // namespace

void save_result(const RealizationResult& res, StateWriter& w) {
    StatePut io(w);
    std::uint16_t version = result_format_version;
    io(version);
    result_v3(io, res, version);
}

void restore_result(RealizationResult& res, StateReader& r, std::uint32_t format) {
    StateGet io(r);
    if (format < 3) return result_v2(io, res);
    std::uint16_t version = 0;
    io(version);
    io.check([&] { return version >= 1 && version <= result_format_version; });
    result_v3(io, res, version);
}

// The field accumulator's open window, described once.
template <class Io, class A>
void CheckpointAccess::accumulator(Io& io, A& a) {
    fields(io, a.out_);
    io(a.window_);
    io(a.start_);
    io(a.current_);
    io(a.window_samples_);
    io(a.min_weight_);
    io(a.wsum_);
    for (int f = 0; f < field_count; ++f)
        io(a.fsum_[f]);
    io(a.touched_);
    io.check([&] {
        const auto nodes = std::size_t(a.out_.grid.size());
        if (a.wsum_.size() != nodes) return false;
        for (int f = 0; f < field_count; ++f)
            if (a.fsum_[f].size() != nodes) return false;
        for (int k : a.touched_)
            if (k < 0 || std::size_t(k) >= nodes) return false;
        return true;
    });
}

void CheckpointAccess::save(const FieldAccumulator& a, StateWriter& w) {
    StatePut io(w);
    accumulator(io, a);
}

void CheckpointAccess::restore(FieldAccumulator& a, StateReader& r) {
    StateGet io(r);
    accumulator(io, a);
}

}  // namespace hopper::engine
