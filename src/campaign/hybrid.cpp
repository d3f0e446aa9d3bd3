#include "hopper/campaign/hybrid.hpp"

#include <thread>
#include <vector>

#include "hopper/campaign/inproc_channel.hpp"

namespace hopper::campaign {

namespace {

class SlottedMaster : public MasterChannel {
  public:
    SlottedMaster(MasterChannel& inner, int threads) : inner_(inner), threads_(threads) {}
    int workers() const override { return inner_.workers() * threads_; }
    void send(int worker, const Message& m) override {
        Message copy = m;
        copy.slot = (worker - 1) % threads_;
        inner_.send((worker - 1) / threads_ + 1, copy);
    }
    std::optional<std::pair<int, Message>> receive(std::chrono::milliseconds timeout) override {
        auto got = inner_.receive(timeout);
        if (!got) return got;
        const int slot = got->second.slot;
        if (slot >= threads_) {
            // From a rank started with another --threads: cannot happen with one command line.
            got->second.kind = MessageKind::error;
            got->second.payload.clear();
        }
        got->first = (got->first - 1) * threads_ + std::min(slot, threads_ - 1) + 1;
        return got;
    }

  private:
    MasterChannel& inner_;
    int threads_;
};

}  // namespace

std::unique_ptr<MasterChannel> slotted_master(MasterChannel& inner, int threads) {
    return std::make_unique<SlottedMaster>(inner, threads);
}

void run_hybrid_worker(WorkerChannel& channel, int threads, const ResumableTaskRunner& run,
                       WorkerOptions options) {
    InProcessChannels local(threads);
    std::vector<std::thread> pool;
    for (int i = 0; i < threads; ++i)
        pool.emplace_back([&, i] { run_worker(local.worker(i), run, options); });
    auto quit_all = [&] {
        for (int i = 1; i <= threads; ++i)
            local.master().send(i, Message::make(MessageKind::quit));
        for (auto& t : pool)
            t.join();
    };
    for (;;) {
        while (auto m = channel.poll()) {
            if (m->kind == MessageKind::quit) return quit_all();
            if (m->slot < 0 || m->slot >= threads) continue;  // not ours (cannot happen)
            local.master().send(m->slot + 1, *m);
        }
        // The threads' messages to the master; the wait also paces the polling of MPI.
        auto r = local.master().receive(std::chrono::milliseconds(2));
        while (r) {
            r->second.slot = r->first - 1;
            channel.send(r->second);
            r = local.master().receive(std::chrono::milliseconds(0));
        }
    }
}

}  // namespace hopper::campaign
