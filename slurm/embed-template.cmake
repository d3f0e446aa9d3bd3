# Compiles slurm/hopper.sbatch.in into the `campaign` executable (for `campaign submit`):
# generates sbatch_template.cpp defining hopper::cli::sbatch_template and adds it to hopper_cli.
# Included from src/cli/CMakeLists.txt; re-runs when the template changes.
set(_tmpl ${CMAKE_CURRENT_LIST_DIR}/hopper.sbatch.in)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${_tmpl})
file(READ ${_tmpl} HOPPER_SBATCH_TEMPLATE)
string(FIND "${HOPPER_SBATCH_TEMPLATE}" ")sbatch\"" _bad)
if(NOT _bad EQUAL -1)
  message(FATAL_ERROR "${_tmpl} must not contain )sbatch\"")
endif()
file(CONFIGURE OUTPUT ${CMAKE_CURRENT_BINARY_DIR}/sbatch_template.cpp
  CONTENT "// Generated from slurm/hopper.sbatch.in by slurm/embed-template.cmake. Do not edit.\n#include \"cli/submit.hpp\"\nnamespace hopper::cli {\nconst char* const sbatch_template = R\"sbatch(@HOPPER_SBATCH_TEMPLATE@)sbatch\";\n}\n"
  @ONLY)
target_sources(hopper_cli PRIVATE ${CMAKE_CURRENT_BINARY_DIR}/sbatch_template.cpp)
