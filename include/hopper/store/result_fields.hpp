#pragma once
// The store's names for the engine's description of the result (engine/field_def.hpp and the
// lists in engine/result.hpp), which the codec, the store file's columns and the JSON of
// `campaign simulate` walk. Nothing is described here: a new member needs no edit.

#include "hopper/engine/field_def.hpp"
#include "hopper/engine/result.hpp"

namespace hopper::store {

using engine::Family;
using engine::FieldDef;
using engine::for_each_diagnostic;
using engine::for_each_event_field;
using engine::for_each_result_field;
using engine::Placement;

}  // namespace hopper::store
