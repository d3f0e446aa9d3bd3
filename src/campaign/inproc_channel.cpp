#include "hopper/campaign/inproc_channel.hpp"

#include <stdexcept>

namespace hopper::campaign {

struct InProcessChannels::Shared {
    std::mutex mutex;
    std::condition_variable to_master_cv;
    std::deque<std::pair<int, Message>> to_master;
    std::vector<std::condition_variable> to_worker_cv;
    std::vector<std::deque<Message>> to_worker;
    int first_id = 1;
    std::size_t sent_down = 0, sent_up = 0;
    explicit Shared(int n)
        : to_worker_cv(static_cast<std::size_t>(n)), to_worker(static_cast<std::size_t>(n)) {}
};

class InProcessChannels::Master : public MasterChannel {
  public:
    explicit Master(std::shared_ptr<Shared> s) : s_(std::move(s)) {}
    int workers() const override { return static_cast<int>(s_->to_worker.size()); }
    void send(int worker, const Message& m) override {
        const int i = worker - s_->first_id;
        if (i < 0 || i >= workers()) throw std::out_of_range("no worker " + std::to_string(worker));
        {
            std::lock_guard lock(s_->mutex);
            s_->to_worker[static_cast<std::size_t>(i)].push_back(m);
            ++s_->sent_down;
        }
        s_->to_worker_cv[static_cast<std::size_t>(i)].notify_one();
    }
    std::optional<std::pair<int, Message>> receive(std::chrono::milliseconds timeout) override {
        std::unique_lock lock(s_->mutex);
        if (!s_->to_master_cv.wait_for(lock, timeout, [&] { return !s_->to_master.empty(); }))
            return std::nullopt;
        auto m = std::move(s_->to_master.front());
        s_->to_master.pop_front();
        return m;
    }

  private:
    std::shared_ptr<Shared> s_;
};

class InProcessChannels::Worker : public WorkerChannel {
  public:
    Worker(std::shared_ptr<Shared> s, int index) : s_(std::move(s)), index_(index) {}
    int id() const override { return s_->first_id + index_; }
    Message receive() override {
        std::unique_lock lock(s_->mutex);
        auto& q = s_->to_worker[static_cast<std::size_t>(index_)];
        s_->to_worker_cv[static_cast<std::size_t>(index_)].wait(lock, [&] { return !q.empty(); });
        Message m = std::move(q.front());
        q.pop_front();
        return m;
    }
    std::optional<Message> poll() override {
        std::lock_guard lock(s_->mutex);
        auto& q = s_->to_worker[static_cast<std::size_t>(index_)];
        if (q.empty()) return std::nullopt;
        Message m = std::move(q.front());
        q.pop_front();
        return m;
    }
    void send(const Message& m) override {
        {
            std::lock_guard lock(s_->mutex);
            s_->to_master.emplace_back(id(), m);
            ++s_->sent_up;
        }
        s_->to_master_cv.notify_one();
    }

  private:
    std::shared_ptr<Shared> s_;
    int index_;
};

InProcessChannels::InProcessChannels(int workers, int first_id)
    : shared_(std::make_shared<Shared>(workers)) {
    if (workers < 1) throw std::invalid_argument("InProcessChannels needs at least one worker");
    shared_->first_id = first_id;
    master_ = std::make_unique<Master>(shared_);
    for (int i = 0; i < workers; ++i)
        workers_.push_back(std::make_unique<Worker>(shared_, i));
}

InProcessChannels::~InProcessChannels() = default;

MasterChannel& InProcessChannels::master() {
    return *master_;
}
WorkerChannel& InProcessChannels::worker(int index) {
    return *workers_.at(static_cast<std::size_t>(index));
}
int InProcessChannels::workers() const {
    return static_cast<int>(workers_.size());
}

std::size_t InProcessChannels::sent_to_workers() const {
    std::lock_guard lock(shared_->mutex);
    return shared_->sent_down;
}

std::size_t InProcessChannels::sent_to_master() const {
    std::lock_guard lock(shared_->mutex);
    return shared_->sent_up;
}

}  // namespace hopper::campaign
