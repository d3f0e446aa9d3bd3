#include "hopper/campaign/worker.hpp"

#include <atomic>
#include <chrono>
#include <exception>
#include <string>

namespace hopper::campaign {

void run_worker(WorkerChannel& channel, const TaskRunner& run, WorkerOptions options) {
    for (;;) {
        const Message m = channel.receive();
        if (m.kind == MessageKind::quit) return;
        if (m.kind != MessageKind::task) continue;  // a stop_now that came after the task ended

        std::atomic<bool> stop{false};
        bool quit = false;
        engine::RunHooks hooks;
        hooks.stop = &stop;
        hooks.progress_interval = options.poll_interval;
        hooks.on_progress = [&](const engine::Progress&) {
            while (auto msg = channel.poll()) {
                if (msg->kind == MessageKind::stop_now) stop = true;
                if (msg->kind == MessageKind::quit) {
                    stop = true;
                    quit = true;
                }
            }
        };
        const auto t0 = std::chrono::steady_clock::now();
        Message reply = Message::make(MessageKind::result, m.task, m.attempt);
        try {
            const engine::RealizationResult r = run(m.task, hooks);
            // Stopped early: the engine ends it as failed ("interrupted"). A realization that
            // finished before it saw the request is a result like any other.
            if (stop && r.status == engine::Status::failed)
                reply.kind = MessageKind::interrupted;
            else
                reply.payload = store::encode_result(r);
        } catch (const std::exception& e) {
            reply.kind = MessageKind::error;
            const std::string what = e.what();
            reply.payload.assign(what.begin(), what.end());
        } catch (...) {
            reply.kind = MessageKind::error;
            const std::string what = "unknown exception";
            reply.payload.assign(what.begin(), what.end());
        }
        reply.seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (quit) return;
        channel.send(reply);
    }
}

}  // namespace hopper::campaign
