// The only translation unit that includes <mpi.h>.
#include "hopper/campaign/mpi.hpp"

#include <mpi.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace hopper::campaign {

namespace {

constexpr int tag = 7;

void check(int rc, const char* what) {
    if (rc != MPI_SUCCESS) {
        char text[MPI_MAX_ERROR_STRING];
        int len = 0;
        MPI_Error_string(rc, text, &len);
        throw std::runtime_error(std::string(what) + ": " +
                                 std::string(text, static_cast<std::size_t>(len)));
    }
}

// Sleeps between polls. A reply often follows within a millisecond (the master stores a result
// and hands out the next task at once), so the first 2 ms poll every ~20 us; after that the
// sleeps double up to 2 ms: a waiting rank costs 1-2 % of a core (measured), and a result or a
// task waits at most ~2 ms to be noticed. (A 10 ms cap halved that CPU but cost ~25 ms per task.)
class Backoff {
  public:
    void wait() {
        const auto waited = std::chrono::steady_clock::now() - start_;
        if (waited < std::chrono::milliseconds(2)) {
            std::this_thread::sleep_for(std::chrono::microseconds(20));
            return;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(us_));
        us_ = std::min(us_ * 2, 2000);
    }

  private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
    int us_ = 100;
};

// Probes for a message from `source`; returns its status when one is waiting.
bool probe(MPI_Comm comm, int source, MPI_Status& status) {
    int flag = 0;
    check(MPI_Iprobe(source, tag, comm, &flag, &status), "MPI_Iprobe");
    return flag != 0;
}

Message receive_probed(MPI_Comm comm, const MPI_Status& status) {
    int count = 0;
    check(MPI_Get_count(&status, MPI_BYTE, &count), "MPI_Get_count");
    core::Bytes buf(static_cast<std::size_t>(count));
    check(MPI_Recv(buf.data(), count, MPI_BYTE, status.MPI_SOURCE, tag, comm, MPI_STATUS_IGNORE),
          "MPI_Recv");
    return decode_message(buf);
}

void send_to(MPI_Comm comm, int dest, const Message& m) {
    const core::Bytes b = encode(m);
    check(MPI_Send(b.data(), static_cast<int>(b.size()), MPI_BYTE, dest, tag, comm), "MPI_Send");
}

class MpiMaster : public MasterChannel {
  public:
    MpiMaster(MPI_Comm comm, int size) : comm_(comm), size_(size) {}
    int workers() const override { return size_ - 1; }
    void send(int worker, const Message& m) override { send_to(comm_, worker, m); }
    std::optional<std::pair<int, Message>> receive(std::chrono::milliseconds timeout) override {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        Backoff backoff;
        for (;;) {
            MPI_Status status;
            if (probe(comm_, MPI_ANY_SOURCE, status))
                return std::pair{status.MPI_SOURCE, receive_probed(comm_, status)};
            if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
            backoff.wait();
        }
    }

  private:
    MPI_Comm comm_;
    int size_;
};

class MpiWorker : public WorkerChannel {
  public:
    MpiWorker(MPI_Comm comm, int rank) : comm_(comm), rank_(rank) {}
    int id() const override { return rank_; }
    Message receive() override {
        Backoff backoff;
        for (;;) {
            MPI_Status status;
            if (probe(comm_, 0, status)) return receive_probed(comm_, status);
            backoff.wait();
        }
    }
    std::optional<Message> poll() override {
        MPI_Status status;
        if (probe(comm_, 0, status)) return receive_probed(comm_, status);
        return std::nullopt;
    }
    void send(const Message& m) override { send_to(comm_, 0, m); }

  private:
    MPI_Comm comm_;
    int rank_;
};

}  // namespace

bool launched_by_mpi() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE",
                          "MPI_LOCALNRANKS", "MV2_COMM_WORLD_SIZE"})
        if (std::getenv(v)) return true;
    return false;
}

// One communicator for the campaign, duplicated from MPI_COMM_WORLD so that no other code's
// messages can match ours.
struct MpiSession::Impl {
    MPI_Comm comm = MPI_COMM_NULL;
};

MpiSession::MpiSession() : impl_(std::make_unique<Impl>()) {
    int initialized = 0;
    MPI_Initialized(&initialized);
    // Funneled: a worker simulates in a second thread, and only the main thread calls MPI.
    if (!initialized) {
        int provided = MPI_THREAD_SINGLE;
        check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
        if (provided < MPI_THREAD_FUNNELED)
            throw std::runtime_error(
                "the MPI library does not allow threads beside the MPI "
                "thread (MPI_THREAD_FUNNELED)");
    }
    check(MPI_Comm_dup(MPI_COMM_WORLD, &impl_->comm), "MPI_Comm_dup");
    check(MPI_Comm_rank(impl_->comm, &rank_), "MPI_Comm_rank");
    check(MPI_Comm_size(impl_->comm, &size_), "MPI_Comm_size");
}

MpiSession::~MpiSession() {
    if (impl_->comm != MPI_COMM_NULL) MPI_Comm_free(&impl_->comm);
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Finalize();
}

std::vector<std::string> MpiSession::hosts() const {
    char name[MPI_MAX_PROCESSOR_NAME] = {};
    int len = 0;
    MPI_Get_processor_name(name, &len);
    std::vector<char> all(rank_ == 0 ? static_cast<std::size_t>(size_) * MPI_MAX_PROCESSOR_NAME
                                     : 1);
    check(MPI_Gather(name, MPI_MAX_PROCESSOR_NAME, MPI_CHAR, all.data(), MPI_MAX_PROCESSOR_NAME,
                     MPI_CHAR, 0, impl_->comm),
          "MPI_Gather");
    std::vector<std::string> out;
    if (rank_ == 0)
        for (int r = 0; r < size_; ++r) {
            const char* p = all.data() + static_cast<std::size_t>(r) * MPI_MAX_PROCESSOR_NAME;
            out.emplace_back(p, strnlen(p, MPI_MAX_PROCESSOR_NAME));
        }
    return out;
}

bool MpiSession::all_ok(bool mine) const {
    int in = mine ? 1 : 0, out = 0;
    check(MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MIN, impl_->comm), "MPI_Allreduce");
    return out == 1;
}

std::unique_ptr<MasterChannel> MpiSession::master_channel() const {
    return std::make_unique<MpiMaster>(impl_->comm, size_);
}

std::unique_ptr<WorkerChannel> MpiSession::worker_channel() const {
    return std::make_unique<MpiWorker>(impl_->comm, rank_);
}

void MpiSession::abort(int code) const {
    MPI_Abort(MPI_COMM_WORLD, code);
    std::_Exit(code);
}

}  // namespace hopper::campaign
