#pragma once
//! \file Embree's error codes in words, for the messages of the modules that use Embree (closest points,
//! rendering).

#include <string>

namespace msd {

//! code: an RTCError (rtcGetDeviceError) as an int. Returns e.g. "out of memory", "unsupported CPU".
std::string embree_error_text(int code);

}  // namespace msd
