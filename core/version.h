#pragma once
//! \file The version of the linked msdeform library, beside the headers' (msdeform/version.h).

#include <string>

#include "msdeform/version.h"

namespace msd {

//! The version of the msdeform library in use, "MAJOR.MINOR.PATCH". Compare it with MSD_VERSION_STRING
//! (the headers' version) to detect headers and libraries from different installs.
const char* version();

//! How the library was built, one line for bug reports: the sparse Cholesky in use, Eigen's version and
//! alignment, and whether it was compiled for the building CPU (MSD_NATIVE).
std::string build_info();

}  // namespace msd
