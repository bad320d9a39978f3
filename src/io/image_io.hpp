// Internal image reading and writing (PNG through stb, EXR through OpenEXR, PFM by hand).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"

namespace penumbra::io {

// Largest width or height read or written (a 2D scene's grid has the same limit).
inline constexpr int kMaxImageSide = 16384;

// A decoded image file: interleaved channels, row 0 at the top.
struct RawImage {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;  // width * height * channels
  bool integer_png = false;   // values came from an 8- or 16-bit PNG, scaled to [0, 1], not decoded
};

// Reads .png, .exr or .pfm (by extension, case-insensitive). Messages name the file. With an
// expected size, an image of another size is refused from its header, before decoding; with
// `max_bytes`, so is one whose decoding (7 floats a pixel at most, with its RGB copy) would take
// more.
Expected<RawImage> read_image(const std::string& path, int expect_width = 0, int expect_height = 0,
                              std::uint64_t max_bytes = 0);

// sRGB transfer functions on [0, 1].
float srgb_to_linear(float v);
float linear_to_srgb(float v);

// A file written under a temporary name beside its target, not yet in place: writing several
// outputs all or nothing stages them all, then publishes them.
// While staged, a temporary file is removed if SIGINT or SIGTERM ends the process (unless the
// program handles those signals itself); every StagedFile must be published or discarded.
struct StagedFile {
  std::string temp, target;
  int slot = -1;  // its place in the signal handler's list (-1: not listed)
};
Expected<StagedFile> stage_pfm(const std::string& path, const ImageRgb& image);
// `world`, when given, goes into the EXR's header as the string attribute "penumbra" (what the
// image holds: "2d fluence", "3d radiance", "3d depth", ...), which image_world reads back.
Expected<StagedFile> stage_exr(const std::string& path, const ImageRgb& image,
                               const std::string& world = "");
// An EXR of named channels of one size (each FLOAT or HALF in the file, floats in memory, planar),
// with string attributes in its header: what a baked atlas is written as.
struct ExrChannel {
  std::string name;
  bool half = false;          // stored as 16-bit floats (writing; reading reports the file's)
  std::vector<float> values;  // width * height, row 0 at the top
};
struct ExrChannels {
  int width = 0, height = 0;
  std::vector<ExrChannel> channels;
  std::vector<std::pair<std::string, std::string>> attributes;  // string attributes only
  // The attribute's value, or null.
  const std::string* attribute(const std::string& name) const;
  // The channel, or null.
  const ExrChannel* channel(const std::string& name) const;
};
Expected<StagedFile> stage_exr_channels(const std::string& path, const ExrChannels& image);
// Reads every string attribute, and the channels `want` names (all where it is empty). Refused
// before decoding: a file that is no EXR, is truncated, has subsampled channels, or whose wanted
// channels would take more than `max_bytes` as floats (0: no limit). Messages name the file.
// `check_header`, where given, sees the attributes (and the size, no channel yet) before any pixel
// is decoded; an error from it is returned as it is.
Expected<ExrChannels> read_exr_channels(
    const std::string& path, std::uint64_t max_bytes = 0,
    const std::function<bool(const std::string&)>& want = {},
    const std::function<Status(const ExrChannels&)>& check_header = {});
// What a Penumbra EXR says it holds (stage_exr's `world`); "" for an EXR without it, another
// format (a PFM cannot say) or a file that cannot be read.
std::string image_world(const std::string& path);
Expected<StagedFile> stage_png8(const std::string& path, int width, int height,
                                const std::vector<unsigned char>& rgb);
// A 16-bit PNG (through libpng) of 1 (grey) or 3 (RGB) channels: the codes are written as given,
// so read_image gives back code / 65535 exactly.
Expected<StagedFile> stage_png16(const std::string& path, int width, int height, int channels,
                                 const std::vector<std::uint16_t>& codes);
// Renames a staged file into place (removing it if that fails); discard removes it.
Status publish(const StagedFile& file);
void discard(const StagedFile& file);

// Writes several files all or nothing: every target is checked first (check_output), each is
// staged by `stage(i)`, and they are renamed into place only when all of them were staged.
Status write_all(const std::vector<std::string>& paths,
                 const std::function<Expected<StagedFile>(std::size_t)>& stage);

// A signal handler for programs that handle SIGINT or SIGTERM themselves and want a second one to
// end them: removes the temporary files being written, then dies of the signal
// (async-signal-safe).
void remove_staged_and_die(int sig);

// Text files (CSV, markdown, SVG), staged like the images; several at once, all or nothing.
Expected<StagedFile> stage_text(const std::string& path, const std::string& text);
Status write_text_files(const std::vector<std::pair<std::string, std::string>>& files);
// The whole content of a text file; `what` names it in the errors ("path: cannot read the scene
// file: no such file"); a pipe or a device is refused ("not a regular file").
Expected<std::string> read_text(const std::string& path, const std::string& what = "the file");

// Writers that stage and publish at once, so the target appears whole or not at all.
Status write_pfm(const std::string& path, const ImageRgb& image);
Status write_exr(const std::string& path, const ImageRgb& image);
Status write_png8(const std::string& path, int width, int height,
                  const std::vector<unsigned char>& rgb);

}  // namespace penumbra::io
