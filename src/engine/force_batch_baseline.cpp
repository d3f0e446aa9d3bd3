// The batched force pass built for the baseline instruction set (flags in CMakeLists.txt).
#define HOPPER_FORCE_NS baseline
#define HOPPER_FORCE_TABLE force_table_baseline
#define HOPPER_FORCE_SIMDLEN 2
#include "force_batch_impl.hpp"
