#include "hopper/campaign/signals.hpp"

#include <csignal>
#include <stdexcept>

namespace hopper::campaign {

namespace {

// Signal handlers can only reach static storage; these are the only process-wide state of the
// campaign layer and are touched by the handler and SignalWatcher alone.
std::atomic<int> signal_count{0};
std::atomic<int> last_signal{0};
std::atomic<int> stop_level{0};
std::atomic<bool> watcher_active{false};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void on_signal(int sig) {
    const int n = signal_count.fetch_add(1) + 1;
    last_signal.store(sig);
    stop_level.store(n >= 2 || sig == SIGTERM ? static_cast<int>(StopLevel::now)
                                              : static_cast<int>(StopLevel::drain));
}

constexpr int watched[] = {SIGINT, SIGTERM, SIGUSR1};
struct sigaction previous[3];

}  // namespace

SignalWatcher::SignalWatcher() {
    if (watcher_active.exchange(true))
        throw std::logic_error("only one SignalWatcher may exist at a time");
    signal_count = 0;
    last_signal = 0;
    stop_level = 0;
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;  // system calls (file I/O, sleeps) resume after the handler
    for (int i = 0; i < 3; ++i)
        sigaction(watched[i], &sa, &previous[i]);
}

SignalWatcher::~SignalWatcher() {
    for (int i = 0; i < 3; ++i)
        sigaction(watched[i], &previous[i], nullptr);
    watcher_active = false;
}

StopLevel SignalWatcher::level() const {
    return static_cast<StopLevel>(stop_level.load());
}

int SignalWatcher::count() const {
    return signal_count.load();
}

std::string SignalWatcher::reason() const {
    switch (last_signal.load()) {
        case SIGINT:
            return "SIGINT";
        case SIGTERM:
            return "SIGTERM";
        case SIGUSR1:
            return "SIGUSR1";
        default:
            return "";
    }
}

void ManualStop::request(StopLevel level, std::string reason) {
    std::lock_guard lock(mutex_);
    reason_ = std::move(reason);
    level_ = level;
}

std::string ManualStop::reason() const {
    std::lock_guard lock(mutex_);
    return reason_;
}

}  // namespace hopper::campaign
