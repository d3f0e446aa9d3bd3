// The reference force pass: the pass of force_batch_impl.hpp with one lane (scalar code at the
// baseline instruction set; flags in CMakeLists.txt). Every batched build gives its bits.
#define HOPPER_FORCE_NS reference
#define HOPPER_FORCE_TABLE force_table_reference
#define HOPPER_FORCE_SIMDLEN 1
#include "force_batch_impl.hpp"
