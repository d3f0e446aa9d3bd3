#include "force_batch.hpp"

#include "hopper/core/error.hpp"

namespace hopper::engine {

std::string to_string(KernelPath p) {
    switch (p) {
        case KernelPath::automatic:
            return "auto";
        case KernelPath::reference:
            return "reference";
        case KernelPath::baseline:
            return "baseline";
        case KernelPath::avx2:
            return "avx2";
        case KernelPath::avx512:
            return "avx512";
        case KernelPath::avx512_gather:
            return "avx512-gather";
    }
    return "?";
}

KernelPath parse_kernel_path(const std::string& s) {
    for (KernelPath p : {KernelPath::automatic, KernelPath::reference, KernelPath::baseline,
                         KernelPath::avx2, KernelPath::avx512, KernelPath::avx512_gather})
        if (s == to_string(p)) return p;
    throw core::ConfigError("unknown force kernel '" + s +
                            "': use auto, reference, baseline, avx2, avx512 or avx512-gather");
}

namespace detail {

bool kernel_available(KernelPath p) {
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    switch (p) {
        case KernelPath::avx512:
        case KernelPath::avx512_gather:
            return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                   __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
                   __builtin_cpu_supports("avx512cd");
        case KernelPath::avx2:
            return __builtin_cpu_supports("avx2");
        default:
            return true;
    }
#else
    return p != KernelPath::avx512 && p != KernelPath::avx512_gather && p != KernelPath::avx2;
#endif
}

KernelPath resolve_kernel(KernelPath wanted) {
    // automatic: the AVX-512 batched pass where the CPU has it, else the reference loop; on an
    // Intel CPU its build with hardware gathers (issue 41: 0.95x the emulated gathers' force
    // time on this project's Xeon; AMD's Zen 4 gathers were measured slower, round 3).
    // Measured on this project's machines (AMD EPYC, Zen 4: `bench_engine --paths`,
    // docs/performance.md): AVX-512 takes about 0.8x the reference's time per particle-step;
    // the AVX2 and baseline builds of the batched pass take 1.0-1.1x (no compressing
    // instruction, and 4 or 2 lanes), so they are not chosen. All give the same bits, so the
    // choice never changes a result.
    if (wanted == KernelPath::automatic) {
        if (!kernel_available(KernelPath::avx512)) return KernelPath::reference;
#if defined(__x86_64__) && defined(__GNUC__)
        if (__builtin_cpu_is("intel")) return KernelPath::avx512_gather;
#endif
        return KernelPath::avx512;
    }
    if (!kernel_available(wanted))
        throw core::ConfigError("the " + to_string(wanted) +
                                " force kernel needs an instruction set this CPU does not have; "
                                "use auto (the best this CPU has), baseline or reference");
    return wanted;
}

const ForceTable& force_table(KernelPath p) {
    switch (p) {
        case KernelPath::avx512:
            return force_table_avx512();
        case KernelPath::avx512_gather:
            return force_table_avx512_gather();
        case KernelPath::avx2:
            return force_table_avx2();
        case KernelPath::baseline:
            return force_table_baseline();
        default:
            return force_table_reference();
    }
}

}  // namespace detail
}  // namespace hopper::engine
