// The batched force pass built for the avx2 instruction set (flags in CMakeLists.txt).
#define HOPPER_FORCE_NS avx2
#define HOPPER_FORCE_TABLE force_table_avx2
#define HOPPER_FORCE_SIMDLEN 4
#include "force_batch_impl.hpp"
