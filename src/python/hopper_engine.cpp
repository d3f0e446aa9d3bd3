// hopper_engine: one realization from Python (docs/usage.md, "The engine from Python"). The
// scene is a sweep file's path or a dict of its sections; the scene, the seed and the JSON are
// those of `campaign simulate --json` (cli/scene_run.hpp, cli/result_output.hpp: the same
// functions), and the JSON text comes back as a dict through Python's json module, so the
// numbers are the command's, bit for bit.
#include <pybind11/pybind11.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/options.hpp"
#include "cli/result_output.hpp"
#include "cli/scene_run.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"

namespace py = pybind11;

namespace {

using hopper::core::ConfigError;

// What a dict scene is called in messages and in the result's "sweep".
const std::string dict_name = "<dict>";
// As the sweep file's own guard (config's parse_toml): a scene needs a few levels.
constexpr int max_depth = 64;

// A signal's exception (Ctrl-C: KeyboardInterrupt) is pending in Python; the run unwinds.
struct Interrupted {};

// "a value of type set", for messages.
std::string type_of(py::handle v) {
    return "a value of type " +
           py::str(py::type::handle_of(v).attr("__name__")).cast<std::string>();
}

// A Python value of a dict scene as a tree for config::parse_sweep: dicts, lists and tuples (and
// numpy arrays, through tolist), str, bool, integers and reals (numpy's too). None goes through
// as null, which the config layer refuses naming the key.
nlohmann::json to_tree(py::handle v, const std::string& where, int depth) {
    const auto fail = [&](const std::string& msg) {
        throw ConfigError(dict_name + ": " + (where.empty() ? "the scene" : where) + msg);
    };
    if (depth > max_depth)
        fail(": nested deeper than " + std::to_string(max_depth) +
             " levels; a sweep file needs a few");
    const py::module_ numbers = py::module_::import("numbers");
    const py::module_ abc = py::module_::import("collections.abc");
    if (v.is_none()) return nullptr;
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>();
    if (py::hasattr(v, "dtype") && py::hasattr(v, "item") &&
        py::str(v.attr("dtype").attr("kind")).cast<std::string>() == "b" &&
        py::len(v.attr("shape")) == 0)
        return v.attr("item")().cast<bool>();  // numpy's bool_
    if (py::isinstance(v, abc.attr("Mapping"))) {
        nlohmann::json o = nlohmann::json::object();
        for (auto item : py::reinterpret_borrow<py::object>(v).attr("items")()) {
            const auto kv = item.cast<py::tuple>();
            if (!py::isinstance<py::str>(kv[0]))
                fail(": the key " + py::repr(kv[0]).cast<std::string>() + " is " + type_of(kv[0]) +
                     "; keys are texts (\"material\", \"mu\")");
            const std::string key = kv[0].cast<std::string>();
            o[key] = to_tree(kv[1], where.empty() ? key : where + "." + key, depth + 1);
        }
        return o;
    }
    if (py::isinstance(v, numbers.attr("Integral"))) {
        const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(v.ptr()));
        if (!i) throw py::error_already_set();
        if (i < py::int_(0)) return i.cast<long long>();
        if (i <= py::int_(std::numeric_limits<std::uint64_t>::max()))
            return i.cast<unsigned long long>();  // above 2^63 - 1: refused by config, with key
        fail(" = " + py::repr(i).cast<std::string>() +
             " is not a 64-bit integer (TOML integers are in [-9223372036854775808, "
             "9223372036854775807])");
    }
    if (py::isinstance(v, numbers.attr("Real"))) return v.cast<double>();
    if (py::hasattr(v, "tolist") && !py::isinstance(v, numbers.attr("Number")))
        return to_tree(v.attr("tolist")(), where, depth);  // a numpy array
    if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
        nlohmann::json a = nlohmann::json::array();
        std::size_t k = 0;
        for (auto e : v)
            a.push_back(to_tree(e, where + "[" + std::to_string(k++) + "]", depth + 1));
        return a;
    }
    fail(": " + type_of(v) +
         " cannot go into a sweep file (numbers, texts, booleans, lists and dicts can)");
    return nullptr;  // not reached
}

// The scene argument: a dict of sections, or a sweep file's path (str or os.PathLike).
struct Scene {
    hopper::config::SweepFile sweep;
    std::string name;  // the result's "sweep": the path as given, or "<dict>"
};

Scene read_scene(py::handle scene) {
    if (py::isinstance(scene, py::module_::import("collections.abc").attr("Mapping")))
        return {hopper::config::parse_sweep_tree(to_tree(scene, "", 0), dict_name), dict_name};
    if (py::isinstance<py::str>(scene) || py::hasattr(scene, "__fspath__")) {
        const py::object path = py::module_::import("os").attr("fspath")(scene);
        if (!py::isinstance<py::str>(path))
            throw py::type_error("scene: a path as bytes; give it as a str");
        const std::string name = path.cast<std::string>();
        return {hopper::config::load_sweep(name), name};
    }
    throw py::type_error(
        "scene: a dict of sweep-file sections ({\"hopper\": {...}, ...}) or the "
        "path of a sweep file, got " +
        type_of(scene));
}

// seed: an integer in [0, 2^64) or a text as `campaign simulate --seed` takes it (the digits, or
// a store's seed_str: 's' and the digits).
std::uint64_t read_seed(py::handle seed) {
    if (py::isinstance<py::str>(seed))
        return hopper::cli::parse_seed_text("seed", seed.cast<std::string>());
    if (py::isinstance<py::bool_>(seed) ||
        !py::isinstance(seed, py::module_::import("numbers").attr("Integral")))
        throw py::type_error("seed: an integer or a text (\"s\" and digits), got " + type_of(seed));
    const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(seed.ptr()));
    if (!i) throw py::error_already_set();
    if (i < py::int_(0) || i > py::int_(std::numeric_limits<std::uint64_t>::max()))
        throw ConfigError("seed = " + py::repr(i).cast<std::string>() +
                          " is not in [0, 18446744073709551615]");
    return i.cast<std::uint64_t>();
}

// point or realization: an integer in [0, max].
long long read_index(py::handle v, const char* name, long long max) {
    if (py::isinstance<py::bool_>(v) ||
        !py::isinstance(v, py::module_::import("numbers").attr("Integral")))
        throw py::type_error(std::string(name) + ": an integer, got " + type_of(v));
    const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(v.ptr()));
    if (!i) throw py::error_already_set();
    if (i < py::int_(0) || i > py::int_(max))
        throw ConfigError(std::string(name) + " = " + py::repr(i).cast<std::string>() +
                          " is not in [0, " + std::to_string(max) + "]");
    return i.cast<long long>();
}

// D_cm or theta_deg: a finite number, as `campaign simulate --D/--theta` takes it.
double read_number(py::handle v, const char* name) {
    if (py::isinstance<py::bool_>(v) ||
        !py::isinstance(v, py::module_::import("numbers").attr("Real")))
        throw py::type_error(std::string(name) + ": a number, got " + type_of(v));
    const double x = v.cast<double>();
    if (!std::isfinite(x))
        throw ConfigError(std::string(name) + " = " + py::str(v).cast<std::string>() +
                          " is not a finite number");
    return x;
}

py::object simulate(py::handle scene_arg, py::handle D_cm, py::handle theta_deg, py::handle seed,
                    py::handle point, py::handle realization) {
    namespace cli = hopper::cli;
    const Scene scene = read_scene(scene_arg);
    cli::SceneRun run;
    if (!point.is_none()) {
        if (!D_cm.is_none() || !theta_deg.is_none())
            throw ConfigError(
                "D_cm and theta_deg cannot be given with point: the point has its "
                "own (its label says which)");
        const std::size_t index =
            py::isinstance<py::str>(point)
                ? cli::point_index(scene.sweep, point.cast<std::string>())
                : static_cast<std::size_t>(read_index(point, "point", 100'000'000));
        const long long r =
            realization.is_none() ? 0 : read_index(realization, "realization", 100'000'000);
        run = cli::point_run(scene.sweep, scene.name, index, static_cast<int>(r));
        if (!seed.is_none()) run.request.seed = read_seed(seed);
    } else {
        if (!realization.is_none())
            throw ConfigError(
                "realization needs point (a point of the sweep's [campaign]); "
                "without it give the seed");
        if (seed.is_none())
            throw ConfigError(
                "seed is missing: give seed=N (as `campaign simulate --seed N`), "
                "or point=... to take the campaign's seed of that realization");
        const double D =
            D_cm.is_none() ? cli::base_number(scene.sweep, "D_cm") : read_number(D_cm, "D_cm");
        const double theta = theta_deg.is_none() ? cli::base_number(scene.sweep, "theta_deg")
                                                 : read_number(theta_deg, "theta_deg");
        run = cli::base_scene_run(scene.sweep, scene.name, D, theta, read_seed(seed));
    }

    // The engine runs without the GIL (other Python threads go on); every 0.1 s of wall time
    // it takes the GIL back for a moment to let Python run its signal handlers, so Ctrl-C
    // (KeyboardInterrupt) ends the run at its next time step, as `campaign run`'s stop does.
    hopper::engine::RealizationResult result;
    bool interrupted = false;
    {
        py::gil_scoped_release no_gil;
        hopper::engine::RunHooks hooks;
        hooks.progress_interval = 1e-12;  // every step
        std::uint64_t steps = 0;
        auto next_look = std::chrono::steady_clock::now();
        hooks.on_progress = [&](const hopper::engine::Progress&) {
            if (++steps % 64 != 0) return;
            const auto now = std::chrono::steady_clock::now();
            if (now < next_look) return;
            next_look = now + std::chrono::milliseconds(100);
            py::gil_scoped_acquire gil;
            if (PyErr_CheckSignals() != 0) throw Interrupted{};
        };
        try {
            result = cli::run_scene(run, hooks);
        } catch (const Interrupted&) {
            interrupted = true;
        }
    }
    if (interrupted) throw py::error_already_set();  // the KeyboardInterrupt, as it was raised
    return py::module_::import("json").attr("loads")(cli::result_json(run.request, result));
}

py::list points(py::handle scene_arg) {
    py::list labels;
    for (const auto& p : read_scene(scene_arg).sweep.campaign.points)
        labels.append(p.label);
    return labels;
}

}  // namespace

PYBIND11_MODULE(hopper_engine, m) {
    m.doc() =
        "One realization of a 2D granular hopper (hopper's engine), the same numbers as "
        "`campaign simulate --json` (docs/usage.md, \"The engine from Python\").";
    // A bad scene or argument: ValueError with the message `campaign` prints.
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const ConfigError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });
    m.def("simulate", &simulate, py::arg("scene"), py::kw_only(), py::arg("D_cm") = py::none(),
          py::arg("theta_deg") = py::none(), py::arg("seed") = py::none(),
          py::arg("point") = py::none(), py::arg("realization") = py::none(),
          R"(Runs one realization and returns its result as a dict.

scene: the path of a sweep file (str or os.PathLike), or a dict of its sections, e.g.
    {"hopper": {"width_cm": 8.0, "particles": 100}, "protocol": {"max_time_s": 3.0}}
    (every key, unit and range: campaigns/README.md; "material.mu" may be written dotted).

Either as `campaign simulate SWEEP --D D_cm --theta theta_deg --seed seed --json`:
    seed (int, or a store's seed_str "s..."), D_cm and theta_deg (default: the scene's own
    hopper.D_cm and hopper.theta_deg): the scene's base sections with that outlet and angle;
or a realization of the sweep's [campaign], as `campaign run` runs it:
    point (its index, from 0, or its label; see points()) and realization (default 0): the
    point's scene and the seed `campaign run` gives it (seed= overrides it).

Returns the dict of `campaign simulate --json` (status, survival_times, ..., events); a
realization that fails numerically returns status "failed" with its message. A bad scene or
argument raises ValueError with the message `campaign` prints. The engine runs without the GIL;
Ctrl-C raises KeyboardInterrupt within a time step.)");
    m.def("points", &points, py::arg("scene"),
          "The labels of the sweep's [campaign] points, in order (point= takes an index into "
          "this list or a label); empty without a [campaign].");
}
