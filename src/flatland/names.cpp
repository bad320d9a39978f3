// Names of methods and options as they appear on the command line and in --json output.
#include "penumbra/render.hpp"

namespace penumbra {

const char* to_string(Method m) {
  switch (m) {
    case Method::rc:
      return "rc";
    case Method::pt:
      return "pt";
  }
  return "?";
}

const char* to_string(MergeFix f) {
  switch (f) {
    case MergeFix::bilinear:
      return "bilinear";
    case MergeFix::none:
      return "none";
    case MergeFix::nearest:
      return "nearest";
  }
  return "?";
}

const char* to_string(Sampler s) {
  switch (s) {
    case Sampler::r1:
      return "r1";
    case Sampler::random:
      return "random";
  }
  return "?";
}

}  // namespace penumbra
