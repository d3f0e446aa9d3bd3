#pragma once
// fuzz_inputs (issue 6, item 4): malformed sweep files and damaged stores. Shared pieces of the
// harness: the deterministic generator of a case, the outcome a case reports, and the two
// families of cases (sweep.cpp, store.cpp; HDF5 forgeries in h5forge.cpp).
//
// Every case is a pure function of (seed, case id): case ids alternate between the families
// (even: sweep file, odd: store), so `fuzz_inputs --seed S --case N` reproduces case N of any run
// with seed S, whatever --cases was.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "hopper/core/random.hpp"

namespace hopper::fuzz {

namespace fs = std::filesystem;

// A small deterministic generator on top of core::Rng.
class Gen {
  public:
    explicit Gen(std::uint64_t seed) : rng_(seed) {}
    std::uint64_t u64() { return rng_.next_u64(); }
    // Uniform in [0, n); n > 0.
    std::size_t below(std::size_t n) { return static_cast<std::size_t>(u64() % n); }
    // Uniform in [lo, hi].
    long long range(long long lo, long long hi) {
        return lo + static_cast<long long>(below(static_cast<std::size_t>(hi - lo + 1)));
    }
    bool chance(double p) { return rng_.uniform() < p; }
    double uniform() { return rng_.uniform(); }
    template <class T>
    const T& pick(const std::vector<T>& v) {
        return v[below(v.size())];
    }
    // A length skewed towards small values, up to max.
    std::size_t skewed(std::size_t max) {
        const double u = rng_.uniform();
        return static_cast<std::size_t>(u * u * u * static_cast<double>(max));
    }

  private:
    core::Rng rng_;
};

// What a case did, written by the child process and classified by the parent.
enum class Category { ok_run, clean_error, crash, hang, bad, known };
std::string_view to_string(Category c);

struct Outcome {
    Category category = Category::ok_run;
    std::string kind;                   // mutation kind, e.g. "number_edge"
    std::string description;            // what exactly was done (file, offset, value, ...)
    std::vector<std::string> messages;  // "<operation>: <message>", one per operation
    std::string bad_reason;             // why BAD (or KNOWN)
    std::string operation;              // the last operation announced (parent side)
    // Marks the case BAD (keeps the first reason).
    void mark_bad(const std::string& why);
    // Records a clean error of an operation (keeps the worst category).
    void clean(const std::string& op, const std::string& message);
    void note(const std::string& op, const std::string& message);
    // Sends kind and description to the parent at once (before the case's operations run), so
    // that a case that crashes or hangs is still described.
    void announce() const;
};

struct Context {
    std::uint64_t seed = 1;
    fs::path workdir;       // scratch space of this run
    fs::path campaigns;     // the shipped sweep files (campaigns/, campaigns/paper/)
    bool keep_all = false;  // keep every case's files (default: only non-clean ones)
};

// Tells the parent which operation of a case starts (shown when the case crashes or hangs).
void announce_operation(const std::string& name);

// Sweep-file cases (sweep.cpp).
void sweep_case(const Context& ctx, std::uint64_t id, Outcome& out);
// Store cases (store.cpp). prepare_stores() builds the undamaged stores once per run, in the
// parent, before any case runs.
void prepare_stores(const Context& ctx);
void store_case(const Context& ctx, std::uint64_t id, Outcome& out);

// HDF5 forgeries (h5forge.cpp): files that are valid HDF5 but not what the store wrote.
// An HDF5 file with unrelated groups and datasets.
void write_unrelated_hdf5(const fs::path& path, Gen& g);
// A file with the store's group names and root attributes (copied from `model`, so that it looks
// in step with the model's journal) whose datasets have wrong types, shapes or lengths.
void write_lookalike_hdf5(const fs::path& path, const fs::path& model, Gen& g);
// Changes one object of an existing store file (type, rank, length, a group for a dataset, a
// dangling or external link, a root attribute of the wrong type, out-of-range index values).
// Returns what it did.
std::string mutate_store_schema(const fs::path& path, Gen& g);

// Small helpers shared by the families.
std::string read_file(const fs::path& p);
void write_file(const fs::path& p, std::string_view bytes);
// The text shortened for a report line (newlines shown as " | ").
std::string one_line(std::string_view s, std::size_t max = 400);
// Whether the text shows a non-finite number ("nan", "inf", ... as whole words), as JSON or
// tables would print one.
bool mentions_nonfinite(std::string_view text);

}  // namespace hopper::fuzz
