// The batched force pass built for the avx512 instruction set with the partners' columns loaded
// by hardware gathers (flags in CMakeLists.txt; KernelPath::avx512_gather).
#define HOPPER_FORCE_NS avx512_gather
#define HOPPER_FORCE_TABLE force_table_avx512_gather
#define HOPPER_FORCE_SIMDLEN 8
#include "force_batch_impl.hpp"
