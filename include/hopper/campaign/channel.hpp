#pragma once
// How the master and the workers talk: a few message kinds over a small channel interface, with
// an MPI implementation (mpi.hpp, the only code that includes <mpi.h>) and an in-process one
// (inproc_channel.hpp: threads, for the single-process run and for tests without mpirun).
//
// master -> worker: task (task id, attempt; payload: the engine state to resume from, or empty),
//                   stop_now (end the running task early, after saving its state when
//                   checkpoints are on), checkpoint_now (save the running task's state), quit
// worker -> master: result (encoded RealizationResult), interrupted (stopped early: no result;
//                   payload: its engine state when checkpoints are on), error (an exception's
//                   message), heartbeat (the running task advances), checkpoint (payload: the
//                   running task's engine state; seconds: worker time it holds)
// Only task ids travel: every process expands the same task list from the same sweep file.

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "hopper/core/bytes.hpp"

namespace hopper::campaign {

enum class MessageKind : std::uint8_t {
    task = 1,
    stop_now = 2,
    quit = 3,
    result = 4,
    interrupted = 5,
    error = 6,
    heartbeat = 7,
    checkpoint = 8,
    checkpoint_now = 9,
};

struct Message {
    MessageKind kind = MessageKind::quit;
    int task = -1;         // task id (index in config::expand_tasks)
    int attempt = 0;       // 1 for the first try
    int slot = 0;          // hybrid runs: the worker thread of a rank the message is for/from
    double seconds = 0.0;  // worker wall time of the task (result, interrupted, error)
    core::Bytes payload;   // result: encode_result(); error: the message text

    static Message make(MessageKind k, int task = -1, int attempt = 0) {
        Message m;
        m.kind = k;
        m.task = task;
        m.attempt = attempt;
        return m;
    }
};

// Versioned, checked wire format (core::DecodeError when a message cannot be read).
core::Bytes encode(const Message& m);
Message decode_message(std::span<const std::uint8_t> bytes);

// The master's end. Workers are numbered 1..workers().
class MasterChannel {
  public:
    virtual ~MasterChannel() = default;
    virtual int workers() const = 0;
    virtual void send(int worker, const Message& m) = 0;
    // The next message from any worker, waiting at most `timeout` without spinning the CPU.
    virtual std::optional<std::pair<int, Message>> receive(std::chrono::milliseconds timeout) = 0;
};

// A worker's end.
class WorkerChannel {
  public:
    virtual ~WorkerChannel() = default;
    virtual int id() const = 0;  // the worker's number (its MPI rank; 0 in a single process)
    // The next message from the master; blocks without spinning the CPU.
    virtual Message receive() = 0;
    // A message if one is waiting (never blocks).
    virtual std::optional<Message> poll() = 0;
    virtual void send(const Message& m) = 0;
};

}  // namespace hopper::campaign
