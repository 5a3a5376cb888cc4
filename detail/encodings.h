#pragma once
//! \file The detail encodings of seed 9.3 by kind, with their typed options: what the multi-scale
//! pipeline and the command line choose from.

#include <memory>
#include <string>
#include <vector>

#include "msdeform/detail/displacement_vectors.h"
#include "msdeform/detail/displacement_volumes.h"
#include "msdeform/detail/encoding.h"
#include "msdeform/detail/normal_displacements.h"

namespace msd {

enum class EncodingKind {
  Vectors,   //!< local-frame displacement vectors (9.3.1); S and B share connectivity
  Normal,    //!< normal displacements (9.3.2)
  Volumes,   //!< displacement volumes (9.3.3), iterative
  Transfer,  //!< deformation transfer (9.3.3)
};

//! "vectors", "normal", "volumes", "transfer".
const char* to_string(EncodingKind kind);
//! The names above, in that order.
std::vector<std::string> encoding_names();
//! The kind of a name above. \throw InvalidInput for another name, listing the known ones.
EncodingKind encoding_kind(const std::string& name);

//! An encoding and its settings; each encoding reads the parts that concern it.
struct EncodingOptions {
  EncodingKind kind = EncodingKind::Normal;
  DisplacementVectorOptions vectors;   //!< Vectors
  NormalDisplacementOptions normal;    //!< the base-point search of Normal, Volumes and Transfer
  DisplacementVolumeOptions volumes;   //!< Volumes
};

//! A new encoding. \throw InvalidInput for an invalid kind.
std::unique_ptr<DetailEncoding> make_encoding(const EncodingOptions& options);

}  // namespace msd
