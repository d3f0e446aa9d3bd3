#pragma once
// Coarse-grained velocity and pressure fields during the discharge (docs/model.md,
// "Coarse-grained fields"; off unless a campaign switches them on).
//
// Sampling: every `sample_interval` of discharge time (shaking excluded), each particle i in the
// grid contributes its velocity (vx, vy, |v|) and its pressure p_i = sum_j |F_n,ij| / (m_i g)
// (all its particle and wall contacts) with a weight w_c(r_i) to the grid node c:
//   - cell kernel: w = 1 for the square cell that contains r_i, 0 elsewhere (the published
//     average over cells);
//   - Gaussian kernel: w = exp(-|r_i - r_c|^2 / (2 s^2)) for the node r_c at the cell centre,
//     cut at 3 s (smooth fields without the cell artefacts near walls).
// Per time window of length `window` (windows tile the discharge time from `start`), a node's
// window value is the weighted mean sum w f / sum w over the window's samples. A node takes part
// in a window when sum w >= min_weight * (samples in the window): min_weight = 0 (any particle)
// for cells, 0.1 for the Gaussian (a particle within about 2 s of the node). The last window
// may be partial (the discharge ended or `end` was reached).
// Per node, the window values are summarised by their count n, mean and M2 = sum of squared
// deviations from the mean (Welford); pieces of different realizations merge exactly with
// Chan et al.'s pairwise formula (FieldMoments::merge). The fluctuation is the standard
// deviation over windows, sqrt(M2 / (n - 1)).
//
// Cost: nothing is allocated or sampled when fields are off. When on, each sample costs one
// extra pass over the neighbour list for the normal forces (System::normal_force_sums) plus
// the binning.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hopper::engine {

enum class FieldKernel { cell, gaussian };
std::string to_string(FieldKernel k);

// The fields' settings (part of SceneParams; lengths in units of d_large, times in s).
struct FieldParams {
    bool enabled = false;
    double window = 0.01;           // s of discharge time per window
    double cell = 2.0;              // cell edge (grid spacing), units of d_large
    double sample_interval = 1e-3;  // s between samples; 0 = every time step
    double start = 0.0;             // s of discharge time: sample only from here ...
    std::optional<double> end;      // ... to here (unset: to the end of the discharge)
    FieldKernel kernel = FieldKernel::cell;
    double kernel_width = 1.0;  // Gaussian standard deviation s, units of d_large
};

inline constexpr int field_count = 4;
enum class Field : int { vx = 0, vy = 1, speed = 2, pressure = 3 };
// "vx", "vy", "speed", "pressure" and their units ("m/s", "m g": pressure is in units of the
// particle's own weight).
std::string_view field_name(Field f);
std::string_view field_unit(Field f);

// Square grid: node/cell (i, j) covers [x0 + i h, x0 + (i+1) h) x [y0 + j h, y0 + (j+1) h);
// flat index j * nx + i; the Gaussian kernel's node is the cell centre.
struct FieldGrid {
    double x0 = 0.0, y0 = 0.0;  // m, lower-left corner
    double cell = 0.0;          // m
    int nx = 0, ny = 0;
    FieldKernel kernel = FieldKernel::cell;
    double kernel_width = 0.0;  // m (Gaussian only)
    int size() const { return nx * ny; }
    bool operator==(const FieldGrid&) const = default;
};

// Per-node summaries over windows; what a realization reports and the store keeps.
struct FieldMoments {
    FieldGrid grid;
    std::vector<std::int64_t> windows;  // per node: windows in which it took part (n)
    std::vector<double> weight;         // per node: sum of weights over all samples
    std::array<std::vector<double>, field_count> mean;  // per node: mean of the window values
    std::array<std::vector<double>, field_count> m2;    // per node: sum of squared deviations
    std::int64_t total_windows = 0;                     // windows with at least one sample
    std::int64_t samples = 0;                           // sample instants
    double t_first = 0.0, t_last = 0.0;  // discharge time of the first and last sample
    // The container's inner outline for plots: centre line of the right-hand wall particles
    // from the outlet upwards (mirror x for the left wall), and the wall particle diameter.
    std::vector<double> outline_x, outline_y;
    double wall_diameter = 0.0;

    // Empty moments on `grid` (all per-node vectors sized grid.size(), zero).
    static FieldMoments zero(const FieldGrid& grid);
    // Adds another piece (e.g. another realization) exactly: n, mean and M2 combine with Chan
    // et al.'s formula; weights, windows and samples add. Throws std::invalid_argument when the
    // grids differ.
    void merge(const FieldMoments& other);
    // Standard deviation over windows at a node, sqrt(M2 / (n - 1)); 0 when n < 2.
    double fluctuation(Field f, int node) const;
};

// Accumulates samples into windows and windows into FieldMoments. Pure numerics: the realization
// feeds it the particle columns; tests feed it directly.
class FieldAccumulator {
  public:
    // `window` s per window, windows tiling the time axis from `start`.
    FieldAccumulator(const FieldGrid& grid, double window, double start);
    // One sample at time t (>= start, non-decreasing). Pressure is per particle, already in
    // units of m g. Particles outside the grid are ignored.
    void sample(double t, std::span<const double> x, std::span<const double> y,
                std::span<const double> vx, std::span<const double> vy,
                std::span<const double> pressure);
    // Closes the open window (if it has samples). Call once at the end; sampling may go on
    // afterwards (a new window starts).
    void close_window();
    const FieldMoments& moments() const { return out_; }
    FieldMoments& moments() { return out_; }

  private:
    friend struct CheckpointAccess;  // checkpoint.cpp: the open window to bytes and back
    void add(int node, double w, const std::array<double, field_count>& f);

    FieldMoments out_;
    double window_, start_;
    std::int64_t current_ = -1;  // index of the open window, -1 = none
    int window_samples_ = 0;
    double min_weight_ = 0.0;
    std::vector<double> wsum_;                           // per node, this window
    std::array<std::vector<double>, field_count> fsum_;  // per node, sum w f, this window
    std::vector<int> touched_;                           // nodes with wsum > 0 this window
};

}  // namespace hopper::engine
