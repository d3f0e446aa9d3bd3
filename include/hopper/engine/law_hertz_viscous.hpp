#pragma once
// The Hertz normal force with viscous ("kinetic") friction and no tangential spring
// (material.normal_law = "hertz", material.tangential_law = "viscous"; docs/model.md, "Contact
// forces"; issue 42): the normal force of HertzSpringLaw, K x^(3/2) - alpha sqrt(mbar K) x^(1/4)
// v_n, and F_t* = -hertz_gt_ratio alpha sqrt(mbar K) x^(1/4) v_t capped at mu |F_n|: the
// tangential dashpot of the Hertz spring law without its spring, as ViscousFrictionLaw is the
// linear law's. No contact history is kept. Registered in laws.hpp.

#include <cmath>

#include "hopper/engine/contact.hpp"

namespace hopper::engine {

struct HertzViscousLaw {
    static constexpr NormalLaw normal = NormalLaw::hertz;
    static constexpr TangentialLaw tangential = TangentialLaw::viscous;
    static constexpr bool has_tangential = true;
    static constexpr bool has_history = false;
    static constexpr bool needs_rstar = true;
    static constexpr bool needs_pair_constants = true;
    HOPPER_HOT_INLINE static void pair_constants(const ContactParams& p, double rstar, double mbar,
                                                 double& K, double& eta0) {
        HertzSpringLaw::pair_constants(p, rstar, mbar, K, eta0);
    }
    template <bool Select = false>
    HOPPER_HOT_INLINE static ContactOutput evaluate(const ContactParams& p, const ContactInput& c,
                                                    double& /*hx*/, double& /*hy*/) {
        const double sx = std::sqrt(c.overlap);          // x^(1/2)
        const double eta = c.hertz_eta * std::sqrt(sx);  // kg/s: alpha sqrt(mbar K) x^(1/4)
        const double v_n = c.vx * c.nx + c.vy * c.ny;
        const double fn = c.hertz_K * c.overlap * sx - eta * v_n;
        return viscous_tangential<Select>(p, c, v_n, fn, p.hertz_gt_ratio * eta);
    }
};

}  // namespace hopper::engine
