#include "cli/analyze.hpp"
#include "cli/cite.hpp"

#include <algorithm>
#include <boost/program_options.hpp>
#include <cstdio>
#include <iostream>

#include "cli/options.hpp"
#include "cli/parse.hpp"
#include "cli/simulate.hpp"
#include "hopper/analysis/store_analysis.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/journal.hpp"
#include "hopper/store/store.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace hopper::cli {

using analysis::Analysis;
using analysis::PointAnalysis;

namespace {

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string num(const std::optional<double>& v, const char* f = "%.4g") {
    return v ? fmt(f, *v) : std::string("-");
}

// A p-value with the digits that matter: 0.28, 0.046, 0.004, <0.001 (never "0.00").
std::string p_text(double p) {
    if (p < 0.001) return "<0.001";
    return fmt(p < 0.1 ? "%.2g" : "%.2f", p);
}

}  // namespace

namespace {

// One group's fits across D (jam rate or avalanche size), as one line of the text output.
void write_fits_line(std::ostream& out, const std::string& group, const stats::JamRateFits& j,
                     std::size_t left_out, const char* left_out_text) {
    out << "  " << group << ": " << j.n_points << " outlet(s) with jams";
    if (left_out > 0) out << ", " << left_out << left_out_text;
    out << "; exponential: "
        << (j.exponential.valid ? "B = " + fmt("%.4g", j.exponential.B) + " 1/m"
                                : j.exponential.reason)
        << "; power law: "
        << (j.power_law.valid ? "gamma = " + fmt("%.3g", j.power_law.gamma) +
                                    ", Dc = " + fmt("%.4g", j.power_law.Dc) + " m"
                              : j.power_law.reason)
        << "; preferred: " << j.preferred << " (" << j.decision << ")\n";
}

void write_avalanche_text(std::ostream& out, const Analysis& a, std::size_t width) {
    char buf[1024];
    out << "avalanches per point (s: grains that crossed the outlet per survival interval; <s>: "
           "censored MLE = grains / jams, +- its standard error <s>/sqrt(jams), 95 % CI; p: "
           "clogging probability per grain 1/<s>; gof p: exponential law of s; arches: found / "
           "jams, mean disks)\n";
    std::snprintf(buf, sizeof buf, "%-*s  %26s  %10s  %6s  %14s\n", static_cast<int>(width),
                  "point", "<s> +- se [95% CI]", "p", "gof p", "arches");
    out << buf;
    for (const auto& p : a.points) {
        const auto& av = p.avalanche;
        std::string s = av.reason.empty() ? "-" : av.reason;
        std::string pc = "-";
        if (av.fit && av.fit->tau && av.fit->tau_lo && av.fit->tau_hi && av.fit->sigma_log_tau) {
            s = fmt("%.4g", *av.fit->tau) + " +- " +
                fmt("%.2g", *av.fit->tau * *av.fit->sigma_log_tau) + " [" +
                fmt("%.3g", *av.fit->tau_lo) + ", " + fmt("%.3g", *av.fit->tau_hi) + "]";
            pc = fmt("%.3g", 1.0 / *av.fit->tau);
        }
        const std::string arches =
            std::to_string(av.arches_found) + "/" + std::to_string(av.arch_jams) +
            (av.arch_mean_size ? ", " + fmt("%.2f", *av.arch_mean_size) : std::string());
        std::snprintf(buf, sizeof buf, "%-*s  %26s  %10s  %6s  %14s\n", static_cast<int>(width),
                      p.label.c_str(), s.c_str(), pc.c_str(),
                      av.gof.valid ? p_text(av.gof.p_value).c_str() : "-", arches.c_str());
        out << buf;
    }
    out << "mean avalanche size <s> versus D (exponential growth vs power-law divergence "
           "<s> = A (Dc - D)^-gamma)\n";
    for (const auto& g : a.groups)
        write_fits_line(out, g.group, g.avalanche, g.avalanche_left_out.size(), " left out");
}

}  // namespace

void write_analysis(std::ostream& out, const Analysis& a) {
    std::size_t width = 5;
    for (const auto& p : a.points)
        width = std::max(width, p.label.size());
    char buf[1024];
    out << "analysis per point (c/f/a/t = complete/failed/arrested/time_limit; avg: plain "
           "average of the survival intervals, biased low by censoring; tau: mean survival time, "
           "censored MLE = flow time / jams, 95 % CI; gof p: exponential law; flow: particles "
           "per second; early/late: p of equal jam rates)\n";
    std::snprintf(buf, sizeof buf, "%-*s  %9s  %5s  %6s  %9s  %22s  %6s  %6s  %16s  %18s  %10s\n",
                  static_cast<int>(width), "point", "c/f/a/t", "jams", "shakes", "avg (s)",
                  "tau (s) [95% CI]", "gof p", "R2", "empty (s) +- sd", "flow (1/s) +- se",
                  "early/late");
    out << buf;
    for (const auto& p : a.points) {
        const std::string cfat = std::to_string(p.n_complete) + "/" + std::to_string(p.n_failed) +
                                 "/" + std::to_string(p.n_arrested) + "/" +
                                 std::to_string(p.n_time_limit);
        std::string tau = "-";
        if (p.fit && p.fit->tau && p.fit->tau_lo && p.fit->tau_hi)
            tau = fmt("%.3g", *p.fit->tau) + " [" + fmt("%.3g", *p.fit->tau_lo) + ", " +
                  fmt("%.3g", *p.fit->tau_hi) + "]";
        else if (p.fit && p.fit->tau_lo)
            tau = "> " + fmt("%.3g", *p.fit->tau_lo);
        const std::string empty =
            num(p.empty_time.mean) + " +- " + num(p.empty_time.std_dev, "%.2g");
        const std::string rate = num(p.rate.mean) + " +- " + num(p.rate.std_err, "%.2g");
        std::snprintf(
            buf, sizeof buf, "%-*s  %9s  %5d  %6d  %9s  %22s  %6s  %6s  %16s  %18s  %10s\n",
            static_cast<int>(width), p.label.c_str(), cfat.c_str(), p.n_jams, p.n_shakes,
            num(p.fit ? p.fit->mean_all : std::nullopt).c_str(), tau.c_str(),
            p.gof.valid ? p_text(p.gof.p_value).c_str() : "-",
            p.line.valid ? fmt("%.3f", p.line.r2).c_str() : "-", empty.c_str(), rate.c_str(),
            p.early_late.valid ? p_text(p.early_late.p_value).c_str() : "-");
        out << buf;
    }
    out << "Beverloo W = C rho_b sqrt(g) (D - k d)^(3/2) per wall angle\n  rho_b: "
        << a.rho_b_source << "\n  " << a.d_definition << '\n';
    for (const auto& g : a.groups) {
        const auto& b = g.beverloo;
        out << "  " << g.group << ": ";
        if (b.valid)
            out << "C = " << fmt("%.4g", b.C) << " +- " << fmt("%.2g", b.C_err)
                << ", k = " << fmt("%.4g", b.k) << " +- " << fmt("%.2g", b.k_err) << " ("
                << b.n_points << " outlets, rho_b = " << fmt("%.4g", b.rho_b)
                << " kg/m^2, d = " << fmt("%.4g", b.d) << " m)\n";
        else
            out << "no fit: " << b.reason << '\n';
    }
    out << "jam rate 1/tau versus D\n";
    for (const auto& g : a.groups)
        write_fits_line(out, g.group, g.jam_rate, g.jam_rate_left_out.size(),
                        " left out (no jams)");
    write_avalanche_text(out, a, width);
    if (std::none_of(a.points.begin(), a.points.end(),
                     [](const PointAnalysis& p) { return p.fields.enabled; }))
        return;
    out << "fields per point (merged over the realizations that did not fail; windows: "
           "windows sampled; cells: with data / all; maxima of the cell means)\n";
    std::snprintf(buf, sizeof buf, "%-*s  %12s  %8s  %11s  %15s  %18s\n", static_cast<int>(width),
                  "point", "realizations", "windows", "cells", "max speed (m/s)",
                  "max pressure (m g)");
    out << buf;
    for (const auto& p : a.points) {
        if (!p.fields.enabled) continue;
        const auto& f = p.fields;
        if (!f.merged) {
            std::snprintf(buf, sizeof buf, "%-*s  ", static_cast<int>(width), p.label.c_str());
            out << buf << (f.error ? "error: " : "no fields: ") << f.reason << '\n';
            continue;
        }
        const std::string cells =
            std::to_string(f.cells_with_data) + "/" + std::to_string(f.merged->grid.size());
        std::snprintf(buf, sizeof buf, "%-*s  %12d  %8lld  %11s  %15s  %18s\n",
                      static_cast<int>(width), p.label.c_str(), f.realizations,
                      static_cast<long long>(f.merged->total_windows), cells.c_str(),
                      fmt("%.3g", f.max_mean_speed).c_str(),
                      fmt("%.3g", f.max_mean_pressure).c_str());
        out << buf;
    }
}

int analyze_store(const fs::path& store, bool json, bool write, std::ostream& out,
                  std::ostream& err, bool* written) {
    const analysis::StoreAnalysis result = analysis::analyze_store(store);
    const Analysis& a = result.analysis;
    if (json) {
        out << result.json << '\n';
    } else {
        write_analysis(out, a);
        // What to cite (issue 43); a store whose physics cannot be read for it still analyzes.
        try {
            write_cite_line(out, store.string(), store_cite_use(store.string()));
        } catch (const std::exception& e) {
            err << "campaign: note: no references listed (" << e.what() << ")" << std::endl;
        }
    }
    out.flush();
    // Inconsistent fields (grids that differ inside a point) are reported and make the exit
    // code 1; everything else is printed and written.
    int code = 0;
    for (const auto& p : a.points)
        if (p.fields.error) {
            err << "campaign: fields left out: " << p.fields.reason << std::endl;
            code = exit_error;
        }
    if (!write) return code;
    // The tables above come from the journal, so they hold every realization stored so far;
    // the run writes /analysis itself when it ends.
    if (store::journal_locked(store::journal_path(store))) {
        err << "campaign: note: /analysis not written: a `campaign run` is writing the store "
               "(the tables above are the realizations stored so far; the run writes /analysis "
               "when it ends)"
            << std::endl;
        return code;
    }
    try {
        analysis::write_analysis_group(store, result);
    } catch (const core::StoreError& e) {
        err << "campaign: analysis not written into the store: " << e.what() << std::endl;
        return exit_error;
    }
    if (written) *written = true;
    if (!json) out << "analysis written to " << store.string() << ":/analysis\n";
    return code;
}

namespace {

po::options_description analyze_options() {
    po::options_description d("analyze options");
    d.add_options()("json", po::bool_switch(), "print one JSON object instead of the tables")  //
        ("no-write", po::bool_switch(), "do not write /analysis into the store")               //
        ("help,h", "show this help");
    return d;
}

}  // namespace

void print_analyze_help(std::ostream& os) {
    os << "usage: campaign analyze STORE.h5 [--json] [--no-write]\n\n"
          "Statistics of every point of a store (survival times: their plain average and the\n"
          "mean survival time tau, the censored exponential MLE, with its 95 % interval;\n"
          "goodness of fit; early/late jam rates; empty times; flow rates in particles per\n"
          "second and kg/s) and across points (Beverloo fit per group, jam rate 1/tau versus\n"
          "D), printed as tables or one JSON object, and written into the store's /analysis\n"
          "group (replacing the previous one). Reads the journal, so it works while a\n"
          "`campaign run` writes the store (every realization stored so far; /analysis is\n"
          "then left to the run, which writes it at its end). Figures: campaign plot STORE.h5\n\n"
          "exit codes: 0 analyzed (and written unless a run is writing the store), 1 no store,\n"
          "            or /analysis could not be written (the HDF5 file is not in step; the\n"
          "            tables are printed anyway), 2 bad command line\n\n"
       << analyze_options();
}

int analyze_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, analyze_options(), "store");
    if (vm.count("help")) {
        print_analyze_help(std::cout);
        return 0;
    }
    const std::string store_path = single_positional(vm, "store", "store", "STORE.h5");
    return analyze_store(store_path, vm["json"].as<bool>(), !vm["no-write"].as<bool>(), std::cout,
                         std::cerr);
}

}  // namespace hopper::cli
