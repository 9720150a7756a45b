// Process-wide allocator tuning for a per-frame pipeline (glibc only; ROS-free).
//
// Every image allocates a few buffers of 0.3-2 MB (pyramids, corner scores) and every change of
// the map size allocates a new covariance (12 MB at 400 landmarks). Above glibc's mmap
// threshold each of those is a fresh mmap whose pages fault in one by one and are unmapped again
// when freed; on a virtual machine that was most of the offline pipeline's time (bench/README.md
// has the numbers). Keeping such blocks in the heap (and not trimming it eagerly) makes their
// memory reused instead.
#pragma once

namespace vi_ekf_slam {

/// Raises glibc's mmap threshold to 32 MB and its trim threshold to 128 MB (the process keeps at
/// most that much freed memory for reuse). Returns false where it is not supported. Idempotent.
bool tuneAllocatorForLargeBuffers();

}  // namespace vi_ekf_slam
