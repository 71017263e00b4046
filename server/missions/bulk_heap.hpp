#pragma once
// While a map import writes its rasters through GDAL, the heap's thresholds are raised (issue 24:
// upload -> first tiles). returnFreedMemoryPromptly (mission_memory.hpp) makes every block of 4 MiB
// or more a fresh mmap and gives an arena's top beyond 4 MiB back on each free: GDAL's COG writer
// allocates and frees buffers of several MiB for every strip of overview and compressed tiles, so
// each strip faulted and zeroed fresh pages. Measured on a 7000² DEM: 14.7 s of CPU for dem.tif,
// 57 % of it in the kernel (page faults, munmap). Inside a BulkHeap (ref-counted across threads)
// blocks up to 256 MiB come from the arenas and the tops are kept; when the last one ends the
// thresholds go back to 4 MiB and malloc_trim(0) returns the free pages, so nothing stays resident.
// A no-op in a process that never called returnFreedMemoryPromptly (glibc's own dynamic thresholds
// already avoid the churn).
namespace rover::missions {

class BulkHeap {
 public:
  BulkHeap();
  ~BulkHeap();
  BulkHeap(const BulkHeap&) = delete;
  BulkHeap& operator=(const BulkHeap&) = delete;

 private:
  bool active_ = false;
};

}  // namespace rover::missions
