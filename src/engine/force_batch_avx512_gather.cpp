// The batched force pass built for the avx512 instruction set with the partners' columns loaded
// by hardware gathers (flags in CMakeLists.txt; KernelPath::avx512_gather). Its loops run 16
// lanes, two 8-double vectors per iteration: two gathers in flight for each column (issue 41:
// 0.94x the force time of 8 lanes on this project's Xeon, docs/performance.md). The lanes change
// how a loop is written, not what an entry computes: the same bits as every path.
#define HOPPER_FORCE_NS avx512_gather
#define HOPPER_FORCE_TABLE force_table_avx512_gather
#define HOPPER_FORCE_SIMDLEN 16
#include "force_batch_impl.hpp"
