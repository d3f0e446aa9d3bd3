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
    }
    return "?";
}

KernelPath parse_kernel_path(const std::string& s) {
    for (KernelPath p : {KernelPath::automatic, KernelPath::reference, KernelPath::baseline,
                         KernelPath::avx2, KernelPath::avx512})
        if (s == to_string(p)) return p;
    throw core::ConfigError("unknown force kernel '" + s +
                            "': use auto, reference, baseline, avx2 or avx512");
}

namespace detail {

bool kernel_available(KernelPath p) {
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    switch (p) {
        case KernelPath::avx512:
            return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                   __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
                   __builtin_cpu_supports("avx512cd");
        case KernelPath::avx2:
            return __builtin_cpu_supports("avx2");
        default:
            return true;
    }
#else
    return p != KernelPath::avx512 && p != KernelPath::avx2;
#endif
}

KernelPath resolve_kernel(KernelPath wanted) {
    // automatic: the reference loop. Measured on this project's machines (AMD EPYC, Zen 4:
    // `bench_engine --paths`, docs/performance.md), every batched path is 1.5x slower than it:
    // the contact law is bound by divisions and square roots, which AVX-512 does not speed up
    // there, and packing costs more than the branch it saves. The batched paths stay selectable
    // (--kernel) and give the same bits.
    if (wanted == KernelPath::automatic) return KernelPath::reference;
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
        case KernelPath::avx2:
            return force_table_avx2();
        default:
            return force_table_baseline();
    }
}

}  // namespace detail
}  // namespace hopper::engine
