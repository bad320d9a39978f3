// Names of methods and options as they appear on the command line and in --json output.
#include "flatland/method.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland {

const char* to_string(Method m) {
  if (int(m) < 0 || std::size_t(m) >= method_table().size()) return "?";
  return entry(m).name;
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

const char* to_string(Storage s) {
  switch (s) {
    case Storage::f32:
      return "f32";
    case Storage::f16:
      return "f16";
  }
  return "?";
}

const char* to_string(Corners c) {
  switch (c) {
    case Corners::half:
      return "half";
    case Corners::walls:
      return "walls";
  }
  return "?";
}

const char* to_string(Device d) {
  switch (d) {
    case Device::cpu:
      return "cpu";
    case Device::gpu:
      return "gpu";
    case Device::auto_:
      return "auto";
  }
  return "?";
}

}  // namespace penumbra::flatland
