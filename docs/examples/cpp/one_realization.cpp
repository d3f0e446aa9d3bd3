// The docs' C++ example (README, "Install and cite"): one tiny realization through the installed
// engine library (hopper::engine), 60 disks in an 8 cm hopper, a second of simulated time. Prints
// its status and jams; exit 0 when it ran. tests/install/install.sh builds and runs it.
#include <iostream>

#include "hopper/core/units.hpp"
#include "hopper/engine/realization.hpp"

int main() {
    using namespace hopper;
    engine::SceneParams p;
    p.hopper.width = 8.0 * core::cm;
    p.hopper.outlet = 3.0 * core::cm;
    p.hopper.theta = 60.0 * core::deg;
    p.particles.count = 60;
    p.material.collision_time = 8.0e-4;
    p.protocol.max_time = 1.0;
    const engine::RealizationResult r = engine::run_realization(p, 1);
    std::cout << "status " << engine::to_string(r.status) << " particles " << r.particles
              << " discharged " << r.discharged << " jams " << r.n_jams << '\n';
    return r.status == engine::Status::failed ? 1 : 0;
}
