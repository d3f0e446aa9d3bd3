// The batched force pass built for the avx512 instruction set (flags in CMakeLists.txt).
#define HOPPER_FORCE_NS avx512
#define HOPPER_FORCE_TABLE force_table_avx512
#define HOPPER_FORCE_SIMDLEN 8
#include "force_batch_impl.hpp"
