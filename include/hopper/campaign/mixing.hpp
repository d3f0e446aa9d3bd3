#pragma once
// No silent mixing of physics in one store. A sweep may extend a store with new points, but when
// a setting that the labels do not show (one the sweep does not vary) has a different value in
// points already in the store, the new points would be pooled with physics they do not share:
// same labels shape, different material, and the fits per group would mix them. run_master refuses
// such a sweep unless RunOptions::allow_mixed (`campaign run --allow-mixed`); the Python analysis
// (analysis/hopper_store.py) then groups by every setting that differs, read from the scene texts.
// Points are compared by their typed settings and parameters (store::PointPlan), never by
// parsing labels or scene texts.
//
// (check_compatible in plan.hpp covers points already in the store: their physics must not change.)

#include <string>
#include <vector>

#include "hopper/store/records.hpp"

namespace hopper::campaign {

struct MixedSetting {
    std::string name;                       // scene parameter (sweep-file name), "material.mu"
    std::string sweep_value;                // its value in every point of the sweep ("absent")
    std::vector<std::string> store_values;  // the other values stored points have, sorted
    std::string store_point;                // a stored point with the first of them
};

// The scene parameters in which a new point of `sweep` (a label not in the store) differs from a
// stored point although their labels do not tell that difference: the labels' settings other
// than D are compared, and a differing setting accounts for the parameters of its section
// (theta_deg for the wall angle; [material] also for the walls, which follow it). The outlet D is
// in every label. Stored points without parameters (an old store whose sweep text could not be
// read back: campaign::restore_settings) are not compared. Empty for a resume or a subset.
std::vector<MixedSetting> mixed_settings(const store::CampaignPlan& stored,
                                         const store::CampaignPlan& sweep);

// "material.mu = 0.5 in this sweep, 0.8 in the store (point 'D_cm=1.9 theta_deg=60')", one line
// per setting.
std::string describe(const std::vector<MixedSetting>& mixed);

}  // namespace hopper::campaign
