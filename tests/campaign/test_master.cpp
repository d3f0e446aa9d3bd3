// The master/worker logic without mpirun: in-process channels, worker threads running
// run_worker() with fake task runners. Dispatch order, load balance, every task stored once,
// the retry policy, drain and stop requests, a worker told to quit mid-task, and a master that
// sleeps (not spins) while it waits.

#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <mutex>
#include <thread>

#include "hopper/campaign/inproc_channel.hpp"
#include "hopper/campaign/master.hpp"
#include "hopper/campaign/worker.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/store.hpp"

namespace hopper::campaign {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

fs::path scratch() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const fs::path dir = fs::path(HOPPER_BINARY_DIR) / "tests" / "campaign" / "tmp" /
                         (std::string(info->test_suite_name()) + "." + info->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

engine::RealizationResult fake_result(std::uint64_t seed, engine::Status status) {
    engine::RealizationResult r;
    r.status = status;
    r.seed = seed;
    r.particles = 10;
    r.survival_times = {0.5, 0.25};
    r.censored = {false, true};
    r.jam_onsets = {0.5};
    r.shakes_per_jam = {1};
    r.n_jams = 1;
    r.empty_time = 0.75;
    r.message = status == engine::Status::failed ? "overlap guard" : "";
    return r;
}

// Sleeps `d` in small steps, calling the progress hook like the engine does; returns false
// (and an "interrupted" result) when the stop flag is raised.
bool cooperative_sleep(std::chrono::milliseconds d, const engine::RunHooks& hooks) {
    const auto end = std::chrono::steady_clock::now() + d;
    while (std::chrono::steady_clock::now() < end) {
        std::this_thread::sleep_for(2ms);
        if (hooks.on_progress) hooks.on_progress({engine::Phase::discharge, 0, 0, 0, 0});
        if (hooks.stop && hooks.stop->load()) return false;
    }
    return true;
}

// A campaign of `n` tasks over two points, a store, workers, and a master.
class Harness {
  public:
    using Behaviour =
        std::function<engine::RealizationResult(const TaskRef&, int call, const engine::RunHooks&)>;

    Harness(int tasks, int workers, Behaviour behaviour, MasterOptions opt = fast_options())
        : store_(scratch() / "s.h5"), channels_(workers), behaviour_(std::move(behaviour)) {
        store::PointPlan a, b;
        a.label = "D_cm=2 theta_deg=60";
        b.label = "D_cm=3 theta_deg=60";
        a.scene = "a\n";
        b.scene = "b\n";
        for (int i = 0; i < tasks; ++i) {
            auto& p = i % 2 == 0 ? a : b;
            p.seeds.push_back(1000 + static_cast<std::uint64_t>(i));
            todo_.push_back(
                TaskRef{i, p.label, p.realizations() - 1, 1000 + static_cast<std::uint64_t>(i)});
        }
        store::RunStartRecord run;
        run.plan.name = "t";
        run.plan.seed = 1;
        run.plan.points = {a, b};
        store_.begin_run(run);
        options_ = opt;
        WorkerOptions wopt;
        if (opt.worker_timeout)
            wopt.heartbeat_interval = heartbeat_interval_for(*opt.worker_timeout);
        for (int w = 0; w < workers; ++w)
            threads_.emplace_back([this, w, wopt] {
                run_worker(
                    channels_.worker(w),
                    [this, w](int task, const engine::RunHooks& h) {
                        int call;
                        {
                            std::lock_guard lock(mutex_);
                            call = ++calls_[task];
                            order_.push_back(task);
                            ran_on_[task].push_back(w + 1);
                        }
                        return behaviour_(todo_.at(static_cast<std::size_t>(task)), call, h);
                    },
                    wopt);
            });
    }
    ~Harness() {
        for (int w = 1; w <= channels_.workers(); ++w)
            channels_.master().send(w, Message::make(MessageKind::quit));
        for (auto& t : threads_)
            t.join();
    }

    static MasterOptions fast_options() {
        MasterOptions o;
        o.progress_interval = 0;
        o.max_wait = 20ms;
        return o;
    }

    MasterReport run() {
        Master m(channels_.master(), store_, stop, options_, log);
        return m.run(todo_, Totals{static_cast<int>(todo_.size()), 0, 0});
    }

    const store::TaskEntry* entry(int task) const {
        const auto& t = todo_.at(static_cast<std::size_t>(task));
        return store_.task(t.label(), t.realization);
    }
    // The reason status gives for a failed or erring task ("" when it lists none).
    std::string reason(int task) const {
        const auto& t = todo_.at(static_cast<std::size_t>(task));
        for (const auto& f : store_.status().failures)
            if (f.label == t.label() && f.realization == t.realization) return f.reason;
        return "";
    }
    std::vector<int> order() {
        std::lock_guard lock(mutex_);
        return order_;
    }
    int calls(int task) {
        std::lock_guard lock(mutex_);
        return calls_[task];
    }
    std::vector<int> ran_on(int task) {
        std::lock_guard lock(mutex_);
        return ran_on_[task];
    }
    store::Store& store() { return store_; }

    // A deadline `seconds` from now, set just before run() (a deadline set before the harness
    // was built would lose the time building the store and the threads took, which a loaded
    // machine makes long).
    void set_deadline_in(double seconds) { options_.deadline = store::unix_now() + seconds; }

    // The cost model's expected seconds of every task (0 = unknown by default).
    void set_expected(double seconds) {
        for (auto& t : todo_)
            t.expected_seconds = seconds;
    }

    ManualStop stop;
    std::ostringstream log;

  private:
    store::Store store_;
    InProcessChannels channels_;
    Behaviour behaviour_;
    MasterOptions options_;
    std::vector<TaskRef> todo_;
    std::vector<std::thread> threads_;
    std::mutex mutex_;
    std::map<int, int> calls_;
    std::map<int, std::vector<int>> ran_on_;
    std::vector<int> order_;
};

engine::RealizationResult ok(const TaskRef& t) {
    return fake_result(t.seed, engine::Status::complete);
}

TEST(Channel, MessagesRoundTripAndAreChecked) {
    Message m = Message::make(MessageKind::result, 42, 2);
    m.seconds = 1.25;
    m.payload = {1, 2, 3};
    const store::Bytes b = encode(m);
    const Message back = decode_message(b);
    EXPECT_EQ(back.kind, MessageKind::result);
    EXPECT_EQ(back.task, 42);
    EXPECT_EQ(back.attempt, 2);
    EXPECT_EQ(back.seconds, 1.25);
    EXPECT_EQ(back.payload, m.payload);
    for (std::size_t n = 0; n < b.size(); ++n)
        EXPECT_THROW(decode_message(std::span(b.data(), n)), core::DecodeError);
    store::Bytes bad = b;
    bad[4] = 99;  // kind
    EXPECT_THROW(decode_message(bad), core::DecodeError);
}

// A target campaign adds its rounds' reports (run.cpp): every field must come through. The
// rounds' checkpoint seconds once did not (a stopped target campaign said "0s kept in
// checkpoints ... 0 realization(s) continued from a checkpoint" after saving two).
TEST(Master, AddRoundKeepsEveryField) {
    campaign::MasterReport one, two, all;
    int k = 1;
    for (auto* r : {&one, &two}) {
        for (int* f :
             {&r->stored, &r->failed, &r->errors, &r->gave_up, &r->interrupted, &r->not_started,
              &r->reassigned, &r->late_identical, &r->late_different, &r->silent_at_end,
              &r->checkpoints_written, &r->resumed, &r->deadline_skipped})
            *f = k++;
        for (double* f :
             {&r->wall_seconds, &r->cpu_seconds, &r->lost_worker_seconds, &r->saved_worker_seconds})
            *f = 0.5 * k++;
    }
    one.stopped_running = true;
    two.stopped = true;
    two.stop_reason = "SIGTERM";
    one.fail_fast = "3 failed alike";
    campaign::add_round(all, one);
    campaign::add_round(all, two);
    EXPECT_EQ(all.stored, one.stored + two.stored);
    EXPECT_EQ(all.failed, one.failed + two.failed);
    EXPECT_EQ(all.errors, one.errors + two.errors);
    EXPECT_EQ(all.gave_up, one.gave_up + two.gave_up);
    EXPECT_EQ(all.interrupted, one.interrupted + two.interrupted);
    EXPECT_EQ(all.not_started, one.not_started + two.not_started);
    EXPECT_EQ(all.reassigned, one.reassigned + two.reassigned);
    EXPECT_EQ(all.late_identical, one.late_identical + two.late_identical);
    EXPECT_EQ(all.late_different, one.late_different + two.late_different);
    EXPECT_EQ(all.silent_at_end, two.silent_at_end);  // the last round's
    EXPECT_EQ(all.checkpoints_written, one.checkpoints_written + two.checkpoints_written);
    EXPECT_EQ(all.resumed, one.resumed + two.resumed);
    EXPECT_EQ(all.deadline_skipped, one.deadline_skipped + two.deadline_skipped);
    EXPECT_DOUBLE_EQ(all.wall_seconds, one.wall_seconds + two.wall_seconds);
    EXPECT_DOUBLE_EQ(all.cpu_seconds, one.cpu_seconds + two.cpu_seconds);
    EXPECT_DOUBLE_EQ(all.lost_worker_seconds, one.lost_worker_seconds + two.lost_worker_seconds);
    EXPECT_DOUBLE_EQ(all.saved_worker_seconds, one.saved_worker_seconds + two.saved_worker_seconds);
    EXPECT_TRUE(all.stopped_running);
    EXPECT_TRUE(all.stopped);
    EXPECT_EQ(all.stop_reason, "SIGTERM");
    EXPECT_EQ(all.fail_fast, "3 failed alike");
}

TEST(Master, EveryTaskIsStoredExactlyOnce) {
    Harness h(24, 3, [](const TaskRef& t, int, const engine::RunHooks& hooks) {
        cooperative_sleep(std::chrono::milliseconds(1 + t.task_id % 5), hooks);
        return ok(t);
    });
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 24);
    EXPECT_FALSE(r.stopped);
    for (int i = 0; i < 24; ++i) {
        EXPECT_EQ(h.calls(i), 1) << "task " << i;
        ASSERT_NE(h.entry(i), nullptr);
        EXPECT_EQ(h.entry(i)->state, store::TaskState::done);
    }
    const auto st = h.store().status();
    EXPECT_EQ(st.done, 24);
    EXPECT_EQ(st.pending, 0);
}

TEST(Master, HandsOutTasksInTheGivenOrder) {
    Harness h(8, 1, [](const TaskRef& t, int, const engine::RunHooks&) { return ok(t); });
    h.run();
    EXPECT_EQ(h.order(), (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
}

TEST(Master, DispatchIsDynamic) {
    // Task 0 is slow: it runs until the last task has started (a condition, not a time: it was
    // 300 ms, which the other 10 tasks could outlast on a loaded machine), so the other worker
    // must take every other task. A master that handed tasks out in a fixed order would leave
    // task 0 waiting until its 30 s bound and the last task on the slow worker.
    std::atomic<int> others_started{0};
    Harness h(11, 2, [&](const TaskRef& t, int, const engine::RunHooks& hooks) {
        if (t.task_id != 0) {
            ++others_started;
            cooperative_sleep(5ms, hooks);
            return ok(t);
        }
        const auto bound = std::chrono::steady_clock::now() + 30s;
        while (others_started < 10 && std::chrono::steady_clock::now() < bound)
            cooperative_sleep(2ms, hooks);
        return ok(t);
    });
    EXPECT_EQ(h.run().stored, 11);
    const int slow_worker = h.ran_on(0).at(0);
    for (int i = 1; i < 11; ++i)
        EXPECT_NE(h.ran_on(i).at(0), slow_worker) << "task " << i;
}

TEST(Master, AnExceptionIsRetriedOnceThenLeftForTheNextRun) {
    Harness h(4, 2, [](const TaskRef& t, int call, const engine::RunHooks&) {
        if (t.task_id == 1 && call == 1) throw std::runtime_error("transient trouble");
        if (t.task_id == 2) throw std::runtime_error("persistent trouble");
        return ok(t);
    });
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 3);
    EXPECT_EQ(r.errors, 3);
    EXPECT_EQ(r.gave_up, 1);
    EXPECT_EQ(h.calls(1), 2);
    EXPECT_EQ(h.calls(2), 2);
    EXPECT_EQ(h.entry(1)->state, store::TaskState::done);
    EXPECT_EQ(h.entry(1)->errors, 1);
    EXPECT_EQ(h.entry(2)->state, store::TaskState::error);
    EXPECT_EQ(h.entry(2)->errors, 2);
    EXPECT_EQ(h.reason(2), "persistent trouble");
    const auto st = h.store().status();
    EXPECT_EQ(st.failed, 1);
    EXPECT_EQ(st.errors, 1);
    ASSERT_EQ(st.failures.size(), 1u);
    EXPECT_EQ(st.failures[0].reason, "persistent trouble");
    EXPECT_NE(h.log.str().find("trying once more"), std::string::npos);
    EXPECT_NE(h.log.str().find("left for the next run"), std::string::npos);
}

TEST(Master, AFailedRealizationIsStoredAndNotRetried) {
    Harness h(3, 1, [](const TaskRef& t, int, const engine::RunHooks&) {
        return fake_result(t.seed,
                           t.task_id == 1 ? engine::Status::failed : engine::Status::complete);
    });
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 3);
    EXPECT_EQ(r.failed, 1);
    EXPECT_EQ(h.calls(1), 1);
    EXPECT_EQ(h.entry(1)->state, store::TaskState::failed);
    EXPECT_EQ(h.reason(1), "overlap guard");
}

TEST(Master, AResultWithTheWrongSeedIsAnError) {
    Harness h(2, 1, [](const TaskRef& t, int, const engine::RunHooks&) {
        return fake_result(t.task_id == 0 ? t.seed + 1 : t.seed, engine::Status::complete);
    });
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 1);
    EXPECT_EQ(h.entry(0)->state, store::TaskState::error);
    EXPECT_NE(h.reason(0).find("has seed 1001, expected 1000"), std::string::npos);
}

TEST(Master, DrainLetsRunningTasksFinishAndStartsNoNewOnes) {
    MasterOptions opt = Harness::fast_options();
    opt.grace = 30;
    Harness* self = nullptr;
    Harness h(
        10, 2,
        [&self](const TaskRef& t, int, const engine::RunHooks& hooks) {
            if (t.task_id == 0) self->stop.request(StopLevel::drain, "SIGUSR1");
            if (!cooperative_sleep(100ms, hooks))
                return fake_result(t.seed, engine::Status::failed);
            return ok(t);
        },
        opt);
    self = &h;
    const MasterReport r = h.run();
    EXPECT_TRUE(r.stopped);
    EXPECT_EQ(r.stop_reason, "SIGUSR1");
    EXPECT_EQ(r.stored, 2);  // the two running when the request came
    EXPECT_EQ(r.interrupted, 0);
    EXPECT_EQ(r.not_started, 8);
    EXPECT_NE(h.log.str().find("may finish within 30s"), std::string::npos) << h.log.str();
}

// Issue 27: collision_time_s = 0.8 ran 18 realizations that all failed at their first steps.
// Three failures of one point before its outlet opened, alike but for their numbers, stop the
// handing out of tasks; failures after the opening (a seed's bad luck) never do.
engine::RealizationResult failed_while_settling(const TaskRef& t, bool opened) {
    auto r = fake_result(t.seed, engine::Status::failed);
    r.message = "while settling: overlap of 0.00" + std::to_string(151 + t.task_id) +
                " m exceeds the allowed 0.0015 m";
    r.diagnostics.settle_steps = 40 + t.task_id;
    r.diagnostics.steps = r.diagnostics.settle_steps + (opened ? 1000 : 0);
    return r;
}

TEST(Master, IdenticalFailuresBeforeTheOutletOpensStopTheCampaign) {
    // One worker: tasks in order, A (even ids) fails, B (odd) completes.
    Harness h(10, 1, [](const TaskRef& t, int, const engine::RunHooks&) {
        return t.task_id % 2 == 0 ? failed_while_settling(t, false) : ok(t);
    });
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 5);  // A#0, B#0, A#1, B#1, A#2
    EXPECT_EQ(r.failed, 3);
    EXPECT_EQ(r.not_started, 5);
    EXPECT_FALSE(r.stopped);
    EXPECT_NE(r.fail_fast.find("3 realizations of 'D_cm=2 theta_deg=60' failed the same way "
                               "before the outlet opened (the last: #2, while settling: overlap"),
              std::string::npos)
        << r.fail_fast;
    EXPECT_NE(h.log.str().find("failing fast"), std::string::npos) << h.log.str();
}

TEST(Master, FailuresAfterTheOutletOpenedDoNotStopTheCampaign) {
    Harness h(10, 1, [](const TaskRef& t, int, const engine::RunHooks&) {
        return t.task_id % 2 == 0 ? failed_while_settling(t, true) : ok(t);
    });
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 10);
    EXPECT_EQ(r.failed, 5);
    EXPECT_TRUE(r.fail_fast.empty()) << r.fail_fast;
}

TEST(Master, DrainStopsRunningTasksWhenTheGraceTimeEnds) {
    MasterOptions opt = Harness::fast_options();
    opt.grace = 0.1;
    Harness* self = nullptr;
    Harness h(
        4, 2,
        [&self](const TaskRef& t, int, const engine::RunHooks& hooks) {
            self->stop.request(StopLevel::drain, "SIGINT");
            if (!cooperative_sleep(10s, hooks)) {
                auto r = fake_result(t.seed, engine::Status::failed);
                r.message = "interrupted (stop requested)";
                return r;
            }
            return ok(t);
        },
        opt);
    self = &h;
    const auto t0 = std::chrono::steady_clock::now();
    const MasterReport r = h.run();
    // Margin: the grace (0.1 s) and the stop take about 0.1 s; 2 s is 20 times that, and far
    // from the 10 s of tasks left to finish (what a drain that ignored the grace would take).
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);
    EXPECT_EQ(r.stored, 0);
    EXPECT_EQ(r.interrupted, 2);
    EXPECT_EQ(h.store().status().pending, 4);  // interrupted tasks run again on resume
}

TEST(Master, StopNowInterruptsAtOnce) {
    Harness* self = nullptr;
    Harness h(3, 1, [&self](const TaskRef& t, int, const engine::RunHooks& hooks) {
        self->stop.request(StopLevel::now, "SIGTERM");
        if (!cooperative_sleep(10s, hooks)) return fake_result(t.seed, engine::Status::failed);
        return ok(t);
    });
    self = &h;
    const auto t0 = std::chrono::steady_clock::now();
    const MasterReport r = h.run();
    // Margin: a stop takes a few ms (the task looks at its flag every 2 ms); 1 s is 100 times
    // that, and a tenth of the 10 s the task would run if not stopped.
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
    EXPECT_EQ(r.interrupted, 1);
    EXPECT_EQ(r.not_started, 2);
    EXPECT_NE(h.log.str().find("SIGTERM: handing out no more tasks; stopping the 1 running"),
              std::string::npos)
        << h.log.str();
}

TEST(Master, SleepsWhileWaiting) {
    // One slow task: the master waits 0.8 s for it and must not spin.
    MasterOptions opt = Harness::fast_options();
    opt.max_wait = 250ms;
    opt.progress_interval = 0.2;
    Harness h(
        1, 1,
        [](const TaskRef& t, int, const engine::RunHooks&) {
            std::this_thread::sleep_for(800ms);
            return ok(t);
        },
        opt);
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 1);
    // No race: the task sleeps 0.8 s whatever the load, and load lengthens the wall time, not
    // the CPU time (a spinning master: 0.8 s of CPU). The first progress line is due at 0.2 s.
    EXPECT_GT(r.wall_seconds, 0.75);
    EXPECT_LT(r.cpu_seconds / r.wall_seconds, 0.05) << r.cpu_seconds << " s of CPU";
    EXPECT_NE(h.log.str().find("campaign: 0/1 done, 1 running, 0 failed"), std::string::npos)
        << h.log.str();
}

// Issue 14, item 4: a worker that goes silent (a hung node; here a task that stops advancing, so
// its worker sends no heartbeat) keeps its realization no longer than the limit: it is reported
// and handed to another worker. Its late result is compared with the stored one, never stored
// twice.
// Margin of the tests below: a worker whose task advances sends a heartbeat every 0.125 s (a
// quarter of the limit), so only one not scheduled for 0.5 s, 4 heartbeats, looks silent.
MasterOptions short_timeout() {
    MasterOptions o = Harness::fast_options();
    o.worker_timeout = 0.5;
    return o;
}

TEST(Master, ASilentWorkersRealizationGoesToAnotherAndItsLateResultIsStoredOnce) {
    std::atomic<bool> second_copy_done{false};
    Harness h(
        4, 2,
        [&](const TaskRef& t, int call, const engine::RunHooks& hooks) {
            if (t.task_id == 0 && call == 1) {
                // Hangs (no progress, so no heartbeat) until the other copy is stored.
                while (!second_copy_done)
                    std::this_thread::sleep_for(5ms);
                std::this_thread::sleep_for(50ms);
            } else if (t.task_id == 0) {
                second_copy_done = true;
            } else {
                cooperative_sleep(300ms, hooks);
            }
            return ok(t);
        },
        short_timeout());
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 4);
    EXPECT_EQ(r.reassigned, 1);
    EXPECT_EQ(r.late_identical, 1);
    EXPECT_EQ(r.late_different, 0);
    EXPECT_EQ(h.ran_on(0), (std::vector<int>{1, 2}));
    EXPECT_EQ(h.store().status().done, 4);
    EXPECT_EQ(h.entry(0)->result->rank, 2) << "the reassigned copy was stored first";
    const std::string log = h.log.str();
    EXPECT_NE(log.find("worker 1 has been silent for"), std::string::npos) << log;
    EXPECT_NE(log.find("running 'D_cm=2 theta_deg=60' #0; handing it to another worker"),
              std::string::npos)
        << log;
    EXPECT_NE(log.find("is identical to the stored one; stored once"), std::string::npos) << log;
}

TEST(Master, ALateResultArrivingFirstIsStoredAndTheOtherCopyOnlyCompared) {
    // The first copy is silent until the second has started (so it is reassigned, however late
    // the master notices: it was 0.8 s against the 0.5 s limit), then returns; the second
    // returns 0.3 s after that (the first copy's result is sent the moment it returns), with a
    // different result. (Each wait bounded by 30 s against a hang.)
    std::atomic<bool> second_started{false}, first_returned{false};
    const auto until = [](const std::atomic<bool>& flag, const engine::RunHooks* hooks) {
        const auto bound = std::chrono::steady_clock::now() + 30s;
        while (!flag && std::chrono::steady_clock::now() < bound) {
            if (hooks)
                cooperative_sleep(2ms, *hooks);
            else
                std::this_thread::sleep_for(2ms);  // silent: no progress, no heartbeat
        }
    };
    Harness h(
        1, 2,
        [&](const TaskRef& t, int call, const engine::RunHooks& hooks) {
            engine::RealizationResult r = ok(t);
            if (call == 1) {
                until(second_started, nullptr);  // silent, then back
                first_returned = true;
            } else {
                second_started = true;
                until(first_returned, &hooks);
                cooperative_sleep(300ms, hooks);
                r.discharged = 77;  // a different result: a bad node
            }
            return r;
        },
        short_timeout());
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 1);
    EXPECT_EQ(r.reassigned, 1);
    EXPECT_EQ(r.late_different, 1);
    EXPECT_EQ(h.store().status().done, 1);
    EXPECT_EQ(h.entry(0)->result->rank, 1) << "the first result to arrive is kept";
    EXPECT_NE(h.log.str().find("is DIFFERENT from the stored one"), std::string::npos)
        << h.log.str();
}

// A worker whose realization advances sends heartbeats and keeps it however long it takes.
TEST(Master, AWorkerThatAdvancesKeepsItsRealizationBeyondTheLimit) {
    Harness h(
        1, 2,
        [&](const TaskRef& t, int, const engine::RunHooks& hooks) {
            cooperative_sleep(1500ms, hooks);
            return ok(t);
        },
        short_timeout());
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 1);
    EXPECT_EQ(r.reassigned, 0) << h.log.str();
    EXPECT_EQ(h.calls(0), 1);
}

TEST(Worker, QuitDuringATaskStopsItAndSendsNothing) {
    InProcessChannels ch(1);
    std::atomic<bool> started{false}, finished{false};
    std::thread worker([&] {
        run_worker(ch.worker(0), [&](int, const engine::RunHooks& hooks) {
            started = true;
            cooperative_sleep(5s, hooks);  // the progress hook unwinds it once stopped
            finished = true;
            return fake_result(1, engine::Status::failed);
        });
    });
    ch.master().send(1, Message::make(MessageKind::task, 0, 1));
    while (!started)
        std::this_thread::sleep_for(1ms);
    const auto t0 = std::chrono::steady_clock::now();
    ch.master().send(1, Message::make(MessageKind::quit));
    worker.join();
    // Margin: the task looks at its flag every 2 ms; 1 s is a fifth of the 5 s it would run.
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
    EXPECT_FALSE(finished) << "the task ran to its end";
    EXPECT_EQ(ch.sent_to_master(), 0u);
}

// Issue 14, item 5: SIGTERM took 30 s on a 10-million-particle scene: the worker looked for the
// master's stop only in the engine's progress hook (every 5 ms of simulated time) and the engine
// looks at its stop flag only every few dozen steps. A model of that engine: slow steps (20 ms
// of wall time each), the hook called as the engine calls it (by simulated time), the stop flag
// read every 50 steps. The stop must take effect within a step or two, not 50.
TEST(Worker, AStopActsWithinAStepHoweverSlowTheStepsAre) {
    InProcessChannels ch(1);
    std::atomic<bool> started{false};
    std::thread worker([&] {
        run_worker(ch.worker(0), [&](int, const engine::RunHooks& hooks) {
            const double dt = 1.6e-5;  // s simulated per step (tau_c / 50)
            double t = 0.0, next_progress = hooks.progress_interval;
            started = true;
            for (int step = 1; step <= 1000; ++step) {
                std::this_thread::sleep_for(20ms);
                t += dt;
                if (hooks.on_progress && hooks.progress_interval > 0 && t >= next_progress) {
                    hooks.on_progress({engine::Phase::settle, t, 0, 0, 0});
                    next_progress += hooks.progress_interval;
                }
                if (step % 50 == 0 && hooks.stop && hooks.stop->load()) break;
            }
            return fake_result(1, engine::Status::failed);
        });
    });
    ch.master().send(1, Message::make(MessageKind::task, 0, 1));
    while (!started)
        std::this_thread::sleep_for(1ms);
    std::this_thread::sleep_for(100ms);
    const auto t0 = std::chrono::steady_clock::now();
    ch.master().send(1, Message::make(MessageKind::stop_now, 0));
    const auto reply = ch.master().receive(30s);
    const auto took = std::chrono::steady_clock::now() - t0;
    ASSERT_TRUE(reply);
    EXPECT_EQ(reply->second.kind, MessageKind::interrupted);
    // Within a step or two (20-40 ms). The bound, 500 ms, leaves a loaded machine 10 times
    // that and still fails a stop that waits for the 50-step check: 45 more steps, 0.9 s.
    EXPECT_LT(took, 500ms) << std::chrono::duration<double>(took).count() << " s";
    ch.master().send(1, Message::make(MessageKind::quit));
    worker.join();
}

TEST(Worker, StaleStopRequestsAreIgnored) {
    InProcessChannels ch(1);
    std::thread worker([&] {
        run_worker(ch.worker(0), [](int task, const engine::RunHooks&) {
            return fake_result(static_cast<std::uint64_t>(task), engine::Status::complete);
        });
    });
    ch.master().send(1, Message::make(MessageKind::stop_now, 0));
    ch.master().send(1, Message::make(MessageKind::task, 5, 1));
    const auto reply = ch.master().receive(5s);
    ASSERT_TRUE(reply);
    EXPECT_EQ(reply->second.kind, MessageKind::result);
    EXPECT_EQ(store::decode_result(reply->second.payload).seed, 5u);
    ch.master().send(1, Message::make(MessageKind::quit));
    worker.join();
}

// Time-aware dispatch (issue 15): with a deadline, a task is handed out only if the cost model
// (scaled by what this run measures) says it ends before deadline - grace; none is started when
// none can, and running ones are stopped at deadline - grace.
TEST(MasterDeadline, NothingStartsThatCannotEndBeforeTheDeadline) {
    MasterOptions opt = Harness::fast_options();
    opt.grace = 0.5;
    opt.measured_seconds = opt.measured_expected = 10.0;  // the cost model measured right
    Harness h(
        4, 2,
        [](const TaskRef& t, int, const engine::RunHooks&) {
            return fake_result(t.seed, engine::Status::complete);
        },
        opt);
    h.set_expected(5.0);  // each needs 5 s; 1.5 s are left
    h.set_deadline_in(2.0);
    const auto t0 = std::chrono::steady_clock::now();
    const MasterReport rep = h.run();
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);  // nothing runs: a few ms
    EXPECT_TRUE(rep.stopped);
    EXPECT_EQ(rep.stop_reason, "the deadline");
    EXPECT_EQ(rep.deadline_skipped, 4);
    EXPECT_EQ(rep.stored, 0);
    EXPECT_TRUE(h.order().empty());
    EXPECT_NE(h.log.str().find("none of the 4 realization(s) left is expected to finish"),
              std::string::npos)
        << h.log.str();
}

// Before anything is measured the estimate is a guess: tasks are handed out (else a campaign
// whose guess is too long would start nothing in any allocation) and stopped at the deadline.
TEST(MasterDeadline, UnmeasuredEstimatesDoNotKeepTasksFromStarting) {
    MasterOptions opt = Harness::fast_options();
    opt.grace = 0.5;
    Harness h(
        2, 2,
        [](const TaskRef& t, int, const engine::RunHooks& hooks) {
            if (!cooperative_sleep(t.task_id == 0 ? 10s : 50ms, hooks))
                return fake_result(t.seed, engine::Status::failed);
            return fake_result(t.seed, engine::Status::complete);
        },
        opt);
    h.set_expected(100.0);   // a guess far beyond the deadline
    h.set_deadline_in(1.5);  // task 1 (50 ms) ends long before deadline - grace (1 s)
    const MasterReport rep = h.run();
    EXPECT_EQ(h.order().size(), 2u);
    EXPECT_EQ(rep.stored, 1);
    EXPECT_EQ(rep.interrupted, 1);
    EXPECT_EQ(rep.stop_reason, "the deadline");
    EXPECT_NE(h.log.str().find("nothing of this campaign is measured yet"), std::string::npos);
}

TEST(MasterDeadline, ShortTasksRunAndARunningOneIsStoppedAtTheDeadline) {
    MasterOptions opt = Harness::fast_options();
    opt.grace = 0.5;
    // Task 0 hangs on (cooperatively) far beyond the deadline; the others take 50 ms.
    Harness h(
        4, 2,
        [](const TaskRef& t, int, const engine::RunHooks& hooks) {
            if (!cooperative_sleep(t.task_id == 0 ? 10s : 50ms, hooks))
                return fake_result(t.seed, engine::Status::failed);
            return fake_result(t.seed, engine::Status::complete);
        },
        opt);
    h.set_expected(0.01);
    h.set_deadline_in(1.5);
    const auto t0 = std::chrono::steady_clock::now();
    const MasterReport rep = h.run();
    const double took =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // Margins: tasks 1-3 need 0.15 s of the 1 s before deadline - grace; the stop there takes
    // a few ms of the 0.5 s before the deadline; task 0 runs from a dispatch a few ms after t0.
    EXPECT_GT(took, 0.8);  // stopped at deadline - grace (1.0 s), not before ...
    EXPECT_LT(took, 1.5);  // ... and before the deadline itself
    EXPECT_TRUE(rep.stopped);
    EXPECT_EQ(rep.stop_reason, "the deadline");
    EXPECT_EQ(rep.stored, 3);
    EXPECT_EQ(rep.interrupted, 1);
    // No checkpoints here: the stopped task's worker time is thrown away, and counted.
    EXPECT_GT(rep.lost_worker_seconds, 0.8);
    EXPECT_EQ(rep.saved_worker_seconds, 0.0);
    ASSERT_NE(h.entry(0), nullptr);
    EXPECT_EQ(h.entry(0)->state, store::TaskState::pending);
}

// Issue 29, item 1: a realization that fails after continuing from its checkpoint (the state
// had a valid checksum but was wrong) is not stored as failed, and one whose state the engine
// refuses is not an error: either way the file goes and the realization starts over from its
// beginning, whose outcome is stored.
TEST(MasterCheckpoint, AFailureAfterContinuingFromACheckpointRestartsFromTheBeginning) {
    const fs::path dir = scratch();
    store::Store st(dir / "s.h5");
    store::PointPlan a;
    a.label = "D_cm=2 theta_deg=60";
    a.scene = "a\n";
    a.seeds = {1000, 1001};
    store::RunStartRecord run;
    run.plan.name = "t";
    run.plan.seed = 1;
    run.plan.points = {a};
    st.begin_run(run);
    std::vector<TaskRef> todo;
    for (int i = 0; i < 2; ++i)
        todo.push_back(TaskRef{i, a.label, i, a.seeds[std::size_t(i)], 0.0, a.physics_hash()});
    CheckpointFiles files(dir / "s.h5", "test");
    const std::vector<std::uint8_t> state{1, 2, 3};
    files.write(CheckpointKey{a.label, 0, 1000, a.physics_hash()}, 5.0, state);
    files.write(CheckpointKey{a.label, 1, 1001, a.physics_hash()}, 5.0, state);
    ASSERT_EQ(files.count(), 2);

    InProcessChannels channels(1);
    std::mutex mutex;
    std::vector<std::size_t> state_sizes;  // per call to task 0
    std::thread worker([&] {
        WorkerOptions wopt;
        wopt.checkpoints = true;
        run_worker(
            channels.worker(0),
            [&](int task, std::span<const std::uint8_t> s, const engine::RunHooks&) {
                if (task == 0) {
                    std::lock_guard lock(mutex);
                    state_sizes.push_back(s.size());
                }
                // Task 1's state is refused by the engine (the runner of run.cpp says so).
                if (task == 1 && !s.empty())
                    throw std::runtime_error(std::string(checkpoint_refused) +
                                             "the checkpoint's state is inconsistent (test)");
                // Task 0's continues and fails; from the beginning both complete.
                return fake_result(todo.at(std::size_t(task)).seed,
                                   s.empty() ? engine::Status::complete : engine::Status::failed);
            },
            wopt);
    });
    MasterOptions opt = Harness::fast_options();
    opt.checkpoints = &files;
    ManualStop stop;
    std::ostringstream log;
    MasterReport rep;
    {
        Master m(channels.master(), st, stop, opt, log);
        rep = m.run(todo, Totals{2, 0, 0});
    }
    channels.master().send(1, Message::make(MessageKind::quit));
    worker.join();
    EXPECT_EQ(rep.stored, 2);
    EXPECT_EQ(rep.failed, 0);
    EXPECT_EQ(rep.errors, 0);
    EXPECT_EQ(st.task(a.label, 1)->state, store::TaskState::done);
    EXPECT_EQ(st.task(a.label, 1)->errors, 0);
    EXPECT_NE(log.str().find("the checkpoint's state is inconsistent (test): the checkpoint of"),
              std::string::npos)
        << log.str();
    ASSERT_EQ(state_sizes.size(), 2u);
    EXPECT_EQ(state_sizes[0], state.size());
    EXPECT_EQ(state_sizes[1], 0u);
    EXPECT_EQ(files.count(), 0);
    EXPECT_EQ(st.task(a.label, 0)->state, store::TaskState::done);
    EXPECT_NE(log.str().find("failed after continuing from its checkpoint"), std::string::npos)
        << log.str();
}

// Issue 29, item 3: a deadline far ahead (9999-12-31T23:59:59Z, the latest --deadline takes)
// overflowed the master's clock: it polled without sleeping, and a drain stopped the running
// realizations at once instead of letting them finish.
TEST(MasterDeadline, AFarDeadlineNeitherSpinsNorCutsADrainShort) {
    MasterOptions opt = Harness::fast_options();
    opt.max_wait = 250ms;
    opt.grace = 30;
    opt.deadline = 253402300799.0;
    Harness* self = nullptr;
    Harness h(
        2, 1,
        [&self](const TaskRef& t, int, const engine::RunHooks& hooks) {
            self->stop.request(StopLevel::drain, "SIGUSR1");
            if (!cooperative_sleep(800ms, hooks))
                return fake_result(t.seed, engine::Status::failed);
            return ok(t);
        },
        opt);
    self = &h;
    const MasterReport r = h.run();
    EXPECT_EQ(r.stored, 1) << h.log.str();  // the running one finished within the grace
    EXPECT_EQ(r.interrupted, 0);
    EXPECT_EQ(r.not_started, 1);
    EXPECT_GT(r.wall_seconds, 0.75);
    EXPECT_LT(r.cpu_seconds / r.wall_seconds, 0.1) << r.cpu_seconds << " s of CPU";
}

}  // namespace
}  // namespace hopper::campaign
