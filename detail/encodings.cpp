#include "msdeform/detail/encodings.h"

#include "msdeform/core/errors.h"
#include "msdeform/detail/deformation_transfer.h"

namespace msd {

const char* to_string(EncodingKind kind) {
  switch (kind) {
    case EncodingKind::Vectors:
      return "vectors";
    case EncodingKind::Normal:
      return "normal";
    case EncodingKind::Volumes:
      return "volumes";
    case EncodingKind::Transfer:
      return "transfer";
  }
  return "invalid";
}

std::vector<std::string> encoding_names() { return {"vectors", "normal", "volumes", "transfer"}; }

EncodingKind encoding_kind(const std::string& name) {
  for (EncodingKind k : {EncodingKind::Vectors, EncodingKind::Normal, EncodingKind::Volumes, EncodingKind::Transfer})
    if (name == to_string(k)) return k;
  throw InvalidInput("unknown detail encoding '" + name + "' (known: vectors, normal, volumes, transfer)");
}

std::unique_ptr<DetailEncoding> make_encoding(const EncodingOptions& o) {
  switch (o.kind) {
    case EncodingKind::Vectors:
      return std::make_unique<DisplacementVectors>(o.vectors);
    case EncodingKind::Normal:
      return std::make_unique<NormalDisplacements>(o.normal);
    case EncodingKind::Volumes:
      return std::make_unique<DisplacementVolumes>(o.volumes, o.normal);
    case EncodingKind::Transfer:
      return std::make_unique<DeformationTransfer>(o.normal);
  }
  throw InvalidInput("make_encoding: invalid EncodingKind " + std::to_string(static_cast<int>(o.kind)));
}

}  // namespace msd
