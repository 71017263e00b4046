#pragma once
// The roverplan version stored with a study and each of its runs (CMake's project version).
#ifndef ROVER_VERSION
#define ROVER_VERSION "unknown"
#endif

namespace rover::studies {

inline constexpr const char* kStudyVersion = ROVER_VERSION;

}  // namespace rover::studies
