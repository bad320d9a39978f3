// The library names options by their RenderOptions field in messages (`rc.probe_spacing`); the
// command line shows its own flag for each instead (--probe-spacing).
#pragma once

#include <string>
#include <utility>

// `message` with every `field` the command line has a flag for replaced by that flag.
inline std::string with_flags(std::string message) {
  static const std::pair<const char*, const char*> kFlags[] = {
      {"`method`", "--method"},
      {"`device`", "--device"},
      {"`bounces`", "--bounces"},
      {"`threads`", "--threads"},
      {"`max_memory`", "--max-memory"},
      {"`distance_field`", "--no-distance-field"},
      {"`blocks`", "--no-blocks"},
      {"`rc.probe_spacing`", "--probe-spacing"},
      {"`rc.directions`", "--directions"},
      {"`rc.branching`", "--branching"},
      {"`rc.interval`", "--interval"},
      {"`rc.cascades`", "--cascades"},
      {"`rc.fix`", "--fix"},
      {"`rc.preaverage`", "--preaverage"},
      {"`rc.extend_length`", "--extend-length"},
      {"`rc.extend`", "--extend"},
      {"`hrc.storage`", "--storage"},
      {"`hrc.cross_blur`", "--no-cross-blur"},
      {"`hrc.near_segment`", "--no-near-segment"},
      {"`pt.spp`", "--spp"},
      {"`pt.seconds`", "--time"},
      {"`pt.nee`", "--nee"},
      {"`pt.sampler`", "--sampler"},
      {"`pt.seed`", "--seed"},
  };
  for (const auto& [field, flag] : kFlags)
    for (std::size_t at = message.find(field); at != std::string::npos;
         at = message.find(field, at))
      message.replace(at, std::string(field).size(), flag);
  return message;
}
