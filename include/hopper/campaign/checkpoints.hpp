#pragma once
// Checkpoint files of realizations (issue 15): the engine's state (engine/checkpoint.hpp) of a
// realization that was stopped or is still running, kept beside the store in STORE.checkpoints/
// as one file per realization, written only by the master. A resumed realization continues from
// its file and ends bit-identical to one that never stopped.
//
// File: "HOPPERCK", file format version, the code version that wrote it, the point's label and
// physics hash (FNV-1a 64 of its canonical scene text), the realization index and seed, the
// worker seconds the state holds, the engine state, and a CRC-32C of everything before it.
// Written crash-safely: a temporary file in the same directory, fsync, rename over the old
// file, fsync of the directory; a crash leaves the old file or the new one, never a mix (a
// temporary left behind is removed by the next write of that realization).
//
// A file of another code version or other physics, or a damaged one, is refused with the reason
// and removed, and the realization restarts from its beginning. The file of a realization whose
// result is stored is removed; the directory too once empty.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "hopper/store/codec.hpp"

namespace hopper::campaign {

// How a worker's error reply starts when the engine refused a checkpoint's state (the runner of
// run.cpp); the master then removes the file and restarts the realization, without counting an
// error against it.
inline constexpr std::string_view checkpoint_refused = "checkpoint refused: ";

struct CheckpointKey {
    std::string label;
    int realization = 0;
    std::uint64_t seed = 0;
    std::uint64_t physics = 0;  // store::PointPlan::physics_hash()
};

struct LoadedCheckpoint {
    store::Bytes state;           // for engine::resume_realization
    double worker_seconds = 0.0;  // worker time the state holds (all attempts so far)
};

class CheckpointFiles {
  public:
    CheckpointFiles(std::filesystem::path store, std::string code_version);
    // STORE.checkpoints (beside STORE.h5 and its journal).
    static std::filesystem::path dir_for(const std::filesystem::path& store);
    const std::filesystem::path& dir() const { return dir_; }
    std::filesystem::path path_of(const CheckpointKey& k) const;

    // Throws core::StoreError when the file cannot be written (what is stored is unaffected).
    void write(const CheckpointKey& k, double worker_seconds, std::span<const std::uint8_t> state);
    // The realization's checkpoint, if there is a usable one. A refused file is removed and
    // `*refusal` says why ("written by code version X, this is Y; the realization restarts").
    std::optional<LoadedCheckpoint> read(const CheckpointKey& k, std::string* refusal);
    // The worker seconds a realization's file holds, from its header only (no checks beyond
    // the label): for the deadline's estimate of what is left.
    std::optional<double> peek_seconds(const CheckpointKey& k) const;
    void remove(const CheckpointKey& k);
    void remove_dir_if_empty();
    // Files in the directory (for status and tests).
    int count() const;

  private:
    std::filesystem::path dir_;
    std::string code_version_;
};

}  // namespace hopper::campaign
