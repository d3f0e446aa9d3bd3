#pragma once
// Returning freed memory to the system (issue 44). glibc keeps the blocks a process freed and
// reuses them; a long-running master whose setup or whose results' temporaries freed a lot would
// otherwise hold them as resident memory for hours. A no-op where the C library has no such call.

namespace hopper::core {

void release_free_memory();

}  // namespace hopper::core
