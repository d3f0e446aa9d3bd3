#pragma once
// Column helpers shared by the System's files (private to the engine).

#include <vector>

namespace hopper::engine::detail {

// col[k] = col[order[k]] for every k (scratch: reused storage).
template <class T>
void permute(std::vector<T>& col, const std::vector<int>& order, std::vector<T>& scratch) {
    if (col.empty()) return;
    scratch.resize(col.size());
    for (std::size_t k = 0; k < order.size(); ++k)
        scratch[k] = col[order[k]];
    col.swap(scratch);
}

// Keeps col[keep[k]] at k, in order; drops the rest.
template <class T>
void compact(std::vector<T>& col, const std::vector<int>& keep) {
    if (col.empty()) return;
    for (std::size_t k = 0; k < keep.size(); ++k)
        col[k] = col[keep[k]];
    col.resize(keep.size());
}

}  // namespace hopper::engine::detail
