// Image files: PNG through stb, EXR through OpenEXR, PFM by hand. Every failure becomes an
// Error naming the file; writers go through a temporary file so a target is never half-written.
#include "io/image_io.hpp"

#include <Imath/half.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStdIO.h>
#include <ImfStringAttribute.h>
#include <ImfTileDescription.h>
#include <ImfVersion.h>
#include <png.h>
#include <stb_image.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "io/json_reader.hpp"
#include "io/path_util.hpp"
#include "penumbra/io.hpp"

namespace penumbra::io {
namespace {

Error fail(const std::string& path, const std::string& what) {
  return Error{path + ": " + what};
}

// errno as words; "I/O error" when a failing call left errno unset.
std::string errno_text(int err) {
  return err != 0 ? std::strerror(err) : "I/O error";
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

Expected<FilePtr> open_for_reading(const std::string& path) {
  errno = 0;
  FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) return fail(path, "cannot open: " + errno_text(errno));
  return f;
}

// Size of what is left in `f` from the current position, or -1 when it cannot be told.
long long remaining_bytes(std::FILE* f) {
  const long here = std::ftell(f);
  if (here < 0 || std::fseek(f, 0, SEEK_END) != 0) return -1;
  const long end = std::ftell(f);
  if (end < 0 || std::fseek(f, here, SEEK_SET) != 0) return -1;
  return static_cast<long long>(end) - here;
}

// The size an image must have (0: any), checked from its header before pixels are decoded so a
// layer of the wrong size costs nothing.
struct Expect {
  int width = 0, height = 0;
  std::uint64_t max_bytes = 0;  // 0: no limit
};

Status check_size(const std::string& path, long long width, long long height, Expect e) {
  if (width <= 0 || height <= 0) {
    return fail(path, "image has zero size (" + std::to_string(width) + " x " +
                          std::to_string(height) + ")");
  }
  if (width > kMaxImageSide || height > kMaxImageSide) {
    return fail(path, "image too large (" + std::to_string(width) + " x " + std::to_string(height) +
                          ", the limit is " + std::to_string(kMaxImageSide) + " per side)");
  }
  // Read, then made RGB float: the decoded values and their copy, 4 + 3 floats a pixel at most.
  const double bytes = double(width) * double(height) * 7 * sizeof(float);
  if (e.max_bytes > 0 && bytes > double(e.max_bytes)) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "reading the %lldx%lld image takes %.0f bytes (%.1f MiB), more than the memory "
                  "limit of %llu bytes (%.1f MiB)",
                  width, height, bytes, bytes / double(1 << 20), (unsigned long long)e.max_bytes,
                  double(e.max_bytes) / double(1 << 20));
    return fail(path, text);
  }
  if (e.width > 0 && (width != e.width || height != e.height)) {
    return fail(path, "the image is " + std::to_string(width) + "x" + std::to_string(height) +
                          ", expected " + std::to_string(e.width) + "x" + std::to_string(e.height) +
                          " (the grid's size)");
  }
  return {};
}

// ---- PNG ---------------------------------------------------------------------------------

std::string malformed_png() {
  const char* why = stbi_failure_reason();  // null if stb recorded no reason
  return std::string("malformed PNG: ") + (why ? why : "unknown error");
}

Expected<std::vector<unsigned char>> read_all(const std::string& path) {
  auto f = open_for_reading(path);
  if (!f) return f.error();
  std::vector<unsigned char> bytes;
  unsigned char chunk[1 << 16];
  for (;;) {
    errno = 0;
    const std::size_t n = std::fread(chunk, 1, sizeof chunk, f->get());
    bytes.insert(bytes.end(), chunk, chunk + n);
    if (n < sizeof chunk) break;
  }
  // A directory opens fine on Linux and only fails on read.
  if (std::ferror(f->get())) return fail(path, "cannot read: " + errno_text(errno));
  return bytes;
}

// stb_image sizes a PNG's buffers from its header, before reading the pixel data, and in int.
// So, before stb sees it: the filtered rows the header promises must fit in what the file can
// hold (deflate expands at most 1032 times), and both they and the decoded pixels must fit in
// an int (a 16-bit RGBA image of 16384^2 overflows stb's sizes). The bit depth is at byte 24 and
// the colour type at byte 25, in the IHDR chunk, which must be whole (33 bytes with the
// signature): stbi_info reads zeros past the end of a file cut inside it and accepts it.
Status check_png_data_size(const std::string& path, const std::vector<unsigned char>& file, int w,
                           int h, int out_channels, bool sixteen) {
  if (file.size() < 33)
    return fail(path, "truncated PNG (" + std::to_string(file.size()) +
                          " bytes: its IHDR chunk ends at byte 33)");
  const unsigned bit_depth = file[24], colour_type = file[25];
  unsigned samples = 1;  // grey (0) and palette (3)
  if (colour_type == 2) samples = 3;
  if (colour_type == 4) samples = 2;
  if (colour_type == 6) samples = 4;
  const std::uint64_t row_bytes = (std::uint64_t(w) * samples * bit_depth + 7) / 8;
  const std::uint64_t filtered = std::uint64_t(h) * (1 + row_bytes);
  const std::uint64_t decoded = std::uint64_t(w) * h * out_channels * (sixteen ? 2 : 1);
  constexpr std::uint64_t kIntMax = std::numeric_limits<int>::max();
  if (filtered > kIntMax || decoded > kIntMax) {
    return fail(path, "PNG too large to decode (" + std::to_string(w) + " x " + std::to_string(h) +
                          ", " + std::to_string(decoded) + " bytes of pixels; the limit is 2 GiB)");
  }
  if (filtered > 1032 * std::uint64_t(file.size())) {
    return fail(path, "truncated PNG (a " + std::to_string(file.size()) +
                          "-byte file cannot hold " + std::to_string(w) + " x " +
                          std::to_string(h) + " pixels)");
  }
  return {};
}

Expected<RawImage> read_png(const std::string& path, Expect e) {
  auto bytes = read_all(path);
  if (!bytes) return bytes.error();
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes->size() < sizeof kSignature ||
      !std::equal(kSignature, kSignature + sizeof kSignature, bytes->begin())) {
    return fail(path, "not a PNG file (bad signature)");
  }
  if (bytes->size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    return fail(path, "file too large");
  }
  const int len = static_cast<int>(bytes->size());
  const unsigned char* data = bytes->data();

  int w = 0, h = 0, comp = 0;
  if (!stbi_info_from_memory(data, len, &w, &h, &comp)) {
    return fail(path, malformed_png());
  }
  // Checked before decoding so a hostile header cannot ask for gigabytes.
  if (Status s = check_size(path, w, h, e); !s) return s.error();
  const bool sixteen = stbi_is_16_bit_from_memory(data, len) != 0;
  if (Status s = check_png_data_size(path, *bytes, w, h, comp, sixteen); !s) return s.error();

  RawImage img;
  if (sixteen) {
    std::unique_ptr<stbi_us, void (*)(void*)> px(
        stbi_load_16_from_memory(data, len, &img.width, &img.height, &img.channels, 0),
        stbi_image_free);
    if (!px) return fail(path, malformed_png());
    const std::size_t n = std::size_t(img.width) * img.height * img.channels;
    img.pixels.resize(n);
    for (std::size_t i = 0; i < n; ++i) img.pixels[i] = px.get()[i] / 65535.0f;
  } else {
    std::unique_ptr<stbi_uc, void (*)(void*)> px(
        stbi_load_from_memory(data, len, &img.width, &img.height, &img.channels, 0),
        stbi_image_free);
    if (!px) return fail(path, malformed_png());
    const std::size_t n = std::size_t(img.width) * img.height * img.channels;
    img.pixels.resize(n);
    for (std::size_t i = 0; i < n; ++i) img.pixels[i] = px.get()[i] / 255.0f;
  }
  if (img.channels < 1 || img.channels > 4) {
    return fail(path, "unsupported PNG channel count " + std::to_string(img.channels));
  }
  img.integer_png = true;
  return img;
}

// ---- PFM ---------------------------------------------------------------------------------

enum class TokenResult { kOk, kEof, kTooLong };

// Reads one whitespace-delimited header token and the single whitespace byte that ends it.
TokenResult read_token(std::FILE* f, std::string& out) {
  out.clear();
  int c = std::fgetc(f);
  while (c != EOF && std::isspace(c)) c = std::fgetc(f);
  while (c != EOF && !std::isspace(c)) {
    if (out.size() >= 64) return TokenResult::kTooLong;
    out.push_back(static_cast<char>(c));
    c = std::fgetc(f);
  }
  return c == EOF ? TokenResult::kEof : TokenResult::kOk;
}

template <class T>
bool parse_number(const std::string& s, T& value) {
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, value);
  return ec == std::errc() && ptr == end;
}

std::uint32_t byteswap32(std::uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

Expected<RawImage> read_pfm(const std::string& path, Expect e) {
  auto file = open_for_reading(path);
  if (!file) return file.error();
  std::FILE* f = file->get();

  std::string magic, ws, hs, ss;
  for (std::string* tok : {&magic, &ws, &hs, &ss}) {
    const TokenResult r = read_token(f, *tok);
    if (r == TokenResult::kTooLong) return fail(path, "bad PFM header (token too long)");
    if (r == TokenResult::kEof) {
      if (std::ferror(f)) return fail(path, "cannot read: " + errno_text(errno));
      return fail(path, "bad PFM header (truncated)");
    }
  }
  int channels = 0;
  if (magic == "PF") {
    channels = 3;
  } else if (magic == "Pf") {
    channels = 1;
  } else {
    return fail(path, "bad PFM header (expected 'PF' or 'Pf', found '" + magic + "')");
  }
  long long width = 0, height = 0;
  double scale = 0;
  if (!parse_number(ws, width) || !parse_number(hs, height)) {
    return fail(path, "bad PFM header (size '" + ws + " " + hs + "')");
  }
  if (!parse_number(ss, scale) || scale == 0 || !std::isfinite(scale)) {
    return fail(path, "bad PFM header (scale '" + ss + "')");
  }
  if (Status s = check_size(path, width, height, e); !s) return s.error();

  // Check the length before allocating, so a lying header cannot ask for gigabytes.
  const std::size_t count = std::size_t(width) * height * channels;
  const std::size_t expected = count * sizeof(float);
  const long long left = remaining_bytes(f);
  if (left >= 0 && static_cast<unsigned long long>(left) < expected) {
    return fail(path, "truncated data (expected " + std::to_string(expected) + " bytes, found " +
                          std::to_string(left) + ")");
  }
  std::vector<float> raw(count);
  errno = 0;
  const std::size_t got = std::fread(raw.data(), sizeof(float), count, f);
  if (got < count) {
    if (std::ferror(f)) return fail(path, "cannot read: " + errno_text(errno));
    return fail(path, "truncated data (expected " + std::to_string(expected) + " bytes, found " +
                          std::to_string(got * sizeof(float)) + ")");
  }
  // Negative scale: little-endian data; positive: big-endian. Its magnitude is not applied.
  const bool file_little = scale < 0;
  if (file_little != (std::endian::native == std::endian::little)) {
    for (float& v : raw) v = std::bit_cast<float>(byteswap32(std::bit_cast<std::uint32_t>(v)));
  }

  RawImage img;
  img.width = static_cast<int>(width);
  img.height = static_cast<int>(height);
  img.channels = channels;
  img.pixels.resize(count);
  // PFM stores the bottom row first; ours has row 0 at the top.
  const std::size_t row = std::size_t(width) * channels;
  for (int y = 0; y < img.height; ++y) {
    std::copy_n(raw.data() + std::size_t(img.height - 1 - y) * row, row,
                img.pixels.data() + std::size_t(y) * row);
  }
  return img;
}

// ---- EXR ---------------------------------------------------------------------------------

long long box_width(const Imath::Box2i& b) {
  return static_cast<long long>(b.max.x) - b.min.x + 1;
}
long long box_height(const Imath::Box2i& b) {
  return static_cast<long long>(b.max.y) - b.min.y + 1;
}

// OpenEXR allocates an attribute's value at the size the file claims for it before reading it (a
// 2.4 KB file claiming an attribute of 1.6 GB asked for 1.6 GB; found by fuzz_atlas). The first
// header is walked here first, as OpenEXR reads it: a name and a type (NUL-terminated, at most
// 255 characters), a 32-bit little-endian size, then the value, which a known type of fixed size
// reads at its own size whatever the size field says, a channel list up to its empty name, a
// string vector string by string, and a preview image at the size its width and height give. A
// size (or a preview, or a string) past the end of the file is refused.
Status check_exr_attribute_sizes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(0, std::ios::end);
  const long long total = static_cast<long long>(in.tellg());
  in.seekg(8);  // the magic number and the version
  auto text = [&](std::string& out) {
    out.clear();
    for (char c; in.get(c);) {
      if (c == '\0') return true;
      if (out.size() == 255) return false;
      out += c;
    }
    return false;
  };
  auto u32 = [&](std::uint32_t& v) {
    unsigned char b[4];
    if (!in.read(reinterpret_cast<char*>(b), 4)) return false;
    v = std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 |
        std::uint32_t(b[3]) << 24;
    return true;
  };
  auto left = [&] { return total - static_cast<long long>(in.tellg()); };
  // The values OpenEXR reads at a fixed size, whatever the size field says.
  static const std::pair<const char*, int> kFixed[] = {{"box2i", 16},
                                                       {"box2f", 16},
                                                       {"compression", 1},
                                                       {"double", 8},
                                                       {"envmap", 1},
                                                       {"float", 4},
                                                       {"int", 4},
                                                       {"lineOrder", 1},
                                                       {"m33f", 36},
                                                       {"m33d", 72},
                                                       {"m44f", 64},
                                                       {"m44d", 128},
                                                       {"rational", 8},
                                                       {"tiledesc", 9},
                                                       {"timecode", 8},
                                                       {"keycode", 28},
                                                       {"v2i", 8},
                                                       {"v2f", 8},
                                                       {"v2d", 16},
                                                       {"v3i", 12},
                                                       {"v3f", 12},
                                                       {"v3d", 24},
                                                       {"chromaticities", 32},
                                                       {"deepImageState", 1}};
  std::string name, type, channel;
  for (int k = 0; k < 100000; ++k) {
    if (!text(name)) return fail(path, "damaged EXR header (an attribute's name)");
    if (name.empty()) return {};  // the header's end
    if (!text(type)) return fail(path, "damaged EXR header (attribute '" + name + "''s type)");
    std::uint32_t size = 0;
    if (!u32(size)) return fail(path, "damaged EXR header (attribute '" + name + "''s size)");
    long long value = std::int32_t(size);
    for (const auto& [t, bytes] : kFixed)
      if (type == t) value = bytes;
    if (type == "chlist") {
      // Channels up to an empty name: a name, then 16 bytes each.
      for (int c = 0;; ++c) {
        if (c == 100000 || !text(channel))
          return fail(path, "damaged EXR header (the channel list)");
        if (channel.empty()) break;
        in.seekg(16, std::ios::cur);
      }
      continue;
    }
    if (type == "preview") {
      std::uint32_t w = 0, h = 0;
      if (!u32(w) || !u32(h)) return fail(path, "damaged EXR header (the preview's size)");
      // Two 32-bit sizes: their product fits 64 unsigned bits, four times it may not.
      const unsigned long long pixels = static_cast<unsigned long long>(w) * h;
      constexpr long long kMost = std::numeric_limits<long long>::max();
      value = pixels > static_cast<unsigned long long>(kMost / 4)
                  ? kMost
                  : 4 * static_cast<long long>(pixels);
    }
    if (type == "stringvector" && value >= 0 && value <= left()) {
      // Strings of their own 32-bit sizes, read until the value's size is used up.
      const long long end = static_cast<long long>(in.tellg()) + value;
      while (static_cast<long long>(in.tellg()) < end) {
        std::uint32_t n = 0;
        if (!u32(n) || std::int32_t(n) < 0 || static_cast<long long>(n) > left())
          return fail(path, "damaged EXR header (attribute '" + name + "''s strings)");
        in.seekg(static_cast<std::streamoff>(n), std::ios::cur);
      }
      continue;
    }
    if (value < 0 || value > left())
      return fail(path, "damaged EXR header (attribute '" + name + "' claims " +
                            std::to_string(value) + " bytes, " + std::to_string(left()) +
                            " are left in the file)");
    in.seekg(static_cast<std::streamoff>(value), std::ios::cur);
  }
  return fail(path, "damaged EXR header (more than 100000 attributes)");
}

// OpenEXR sizes its line and tile buffers from the header as it opens a file, before the size
// can be checked (a 229-byte file claiming 115720 columns asked for 2.2 GB): the header is read
// alone first. Throws what OpenEXR throws on a damaged header.
Status check_exr_header(const std::string& path, Expect e) {
  Imf::StdIFStream in(path.c_str());
  char head[8];
  in.read(head, sizeof head);
  if (!Imf::isImfMagic(head)) return fail(path, "not an EXR file (bad magic number)");
  if (Status s = check_exr_attribute_sizes(path); !s) return s;
  std::uint32_t bits = 0;  // little-endian in the file; unsigned, so high bits cannot overflow
  for (int i = 7; i >= 4; --i) bits = bits << 8 | static_cast<unsigned char>(head[i]);
  int version = std::bit_cast<int>(bits);
  Imf::Header header;
  header.readFrom(in, version);  // the first part's header in a multi-part file
  const Imath::Box2i& dw = header.dataWindow();
  if (Status s = check_size(path, box_width(dw), box_height(dw), e); !s) return s;
  if (header.hasTileDescription()) {
    const Imf::TileDescription& t = header.tileDescription();
    if (t.xSize == 0 || t.ySize == 0 || t.xSize > unsigned(kMaxImageSide) ||
        t.ySize > unsigned(kMaxImageSide))
      return fail(path, "bad EXR tile size (" + std::to_string(t.xSize) + " x " +
                            std::to_string(t.ySize) + ")");
  }
  return {};
}

Expected<RawImage> read_exr(const std::string& path, Expect e) {
  // Open once ourselves for a plain errno message on a missing or unreadable file.
  if (auto f = open_for_reading(path); !f) return f.error();
  try {
    if (Status s = check_exr_header(path, e); !s) return s.error();
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const long long width = box_width(dw), height = box_height(dw);
    if (Status s = check_size(path, width, height, e); !s) return s.error();
    // Every block of pixels must be in the file before the pixels are allocated, so that a
    // few kilobytes claiming 16384^2 cannot ask for gigabytes (as for PFM above).
    if (!file.isComplete()) return fail(path, "truncated or damaged EXR (pixel data missing)");

    const Imf::ChannelList& list = file.header().channels();
    std::vector<std::string> names;
    if (list.findChannel("R") && list.findChannel("G") && list.findChannel("B")) {
      names = {"R", "G", "B"};  // A, if any, is not needed
    } else if (list.findChannel("Y")) {
      names = {"Y"};
    } else {
      std::string all;
      for (auto it = list.begin(); it != list.end(); ++it) {
        names.push_back(it.name());
        all += (all.empty() ? "" : ", ") + std::string(it.name());
      }
      if (names.size() != 1) {
        return fail(path, "no R, G, B or Y channel and not a single channel (channels: " +
                              (all.empty() ? std::string("none") : all) + ")");
      }
    }
    for (const std::string& name : names) {
      const Imf::Channel* ch = list.findChannel(name);
      if (ch->xSampling != 1 || ch->ySampling != 1) {
        return fail(path, "subsampled channel '" + name + "' is not supported");
      }
    }

    RawImage img;
    img.width = static_cast<int>(width);
    img.height = static_cast<int>(height);
    img.channels = static_cast<int>(names.size());
    img.pixels.resize(std::size_t(img.width) * img.height * img.channels);
    const std::size_t xs = sizeof(float) * img.channels;
    const std::size_t ys = xs * img.width;
    Imf::FrameBuffer fb;
    for (int c = 0; c < img.channels; ++c) {
      // Make() offsets the base so that data-window pixel (min.x, min.y) lands at index 0.
      fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, img.pixels.data() + c, dw, xs, ys));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return img;
  } catch (const std::exception& e) {
    return fail(path, std::string("cannot read EXR: ") + e.what());
  } catch (...) {
    return fail(path, "cannot read EXR: unknown error");
  }
}

// Collects an EXR file in memory, so the bytes reach disk through the same atomic path.
class MemoryOStream : public Imf::OStream {
 public:
  explicit MemoryOStream(const char* name) : Imf::OStream(name) {}
  void write(const char c[], int n) override {
    if (pos_ + n > bytes_.size()) bytes_.resize(pos_ + n);
    std::memcpy(bytes_.data() + pos_, c, n);
    pos_ += n;
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = pos; }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
  std::size_t pos_ = 0;
};

// ---- Atomic writing ----------------------------------------------------------------------

// Staged files are removed when SIGINT or SIGTERM ends the process while they exist: their
// names sit in fixed slots that a signal handler can read without allocating or locking, and
// while any is staged, a signal whose disposition is the default one goes to a handler that
// unlinks them (unlink is async-signal-safe), then dies of the signal as it would have. A
// program with its own handler (the path tracer's Ctrl-C, the painter) keeps it and finishes
// the writing itself. SIGKILL cannot be caught: docs/RELIABILITY.md says what it leaves.
namespace staging {

constexpr int kSlots = 64;  // staged files at once; beyond that they are not cleaned up
constexpr std::size_t kPathBytes = 4096;
enum : int { kFree, kFilling, kReady };
struct Slot {
  std::atomic<int> state{kFree};
  char path[kPathBytes];
};
Slot slots[kSlots];
constexpr int kSignals[] = {SIGINT, SIGTERM};
std::mutex mutex;  // guards `staged` and the handlers' installation
int staged = 0;
struct sigaction previous[2];
bool installed[2] = {false, false};
// SIGXFSZ (past `ulimit -f`) is ignored while files are staged, so that the write fails with
// EFBIG and the temporary file is removed as for any failed write, instead of the process dying
// with it in place.
struct sigaction previous_xfsz;
bool ignoring_xfsz = false;

extern "C" void remove_staged_and_die(int sig) {
  for (Slot& s : slots)
    if (s.state.load(std::memory_order_acquire) == kReady) ::unlink(s.path);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

// Takes a slot for `temp` (-1: none free or the name too long).
int hold(const std::string& temp) {
  int slot = -1;
  if (temp.size() < kPathBytes)
    for (int i = 0; i < kSlots && slot < 0; ++i) {
      int expected = kFree;
      if (slots[i].state.compare_exchange_strong(expected, kFilling)) slot = i;
    }
  if (slot < 0) return -1;
  std::memcpy(slots[slot].path, temp.c_str(), temp.size() + 1);
  slots[slot].state.store(kReady, std::memory_order_release);
  std::lock_guard<std::mutex> lock(mutex);
  if (staged++ == 0)
    for (int k = 0; k < 2; ++k) {
      struct sigaction now {};
      ::sigaction(kSignals[k], nullptr, &now);
      installed[k] = now.sa_handler == SIG_DFL && !(now.sa_flags & SA_SIGINFO);
      if (!installed[k]) continue;
      struct sigaction ours {};
      ours.sa_handler = remove_staged_and_die;
      sigemptyset(&ours.sa_mask);
      ::sigaction(kSignals[k], &ours, &previous[k]);
    }
  if (staged == 1) {
    struct sigaction now {};
    ::sigaction(SIGXFSZ, nullptr, &now);
    ignoring_xfsz = now.sa_handler == SIG_DFL && !(now.sa_flags & SA_SIGINFO);
    if (ignoring_xfsz) {
      struct sigaction ignore {};
      ignore.sa_handler = SIG_IGN;
      sigemptyset(&ignore.sa_mask);
      ::sigaction(SIGXFSZ, &ignore, &previous_xfsz);
    }
  }
  return slot;
}

void release(int slot) {
  if (slot < 0) return;
  std::lock_guard<std::mutex> lock(mutex);
  slots[slot].state.store(kFree, std::memory_order_release);
  if (--staged == 0)
    for (int k = 0; k < 2; ++k) {
      if (!installed[k]) continue;
      struct sigaction now {};
      ::sigaction(kSignals[k], nullptr, &now);
      // A program that installed its own handler meanwhile keeps it.
      if (now.sa_handler == remove_staged_and_die) ::sigaction(kSignals[k], &previous[k], nullptr);
      installed[k] = false;
    }
  if (staged == 0 && ignoring_xfsz) {
    ::sigaction(SIGXFSZ, &previous_xfsz, nullptr);
    ignoring_xfsz = false;
  }
}

}  // namespace staging

std::string temp_name(const std::string& path) {
  // pid plus a counter: unique across processes and across threads of this one.
  static std::atomic<unsigned> counter{0};
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

// Writes through `fill(FILE*) -> bool` into a temporary file beside `path`; nothing appears at
// `path` yet. On failure the temporary file is removed.
template <class Fill>
Expected<StagedFile> stage(const std::string& path, Fill&& fill) {
  if (Status s = check_output(path); !s) return s.error();
  const std::string tmp = temp_name(path);
  const int slot = staging::hold(tmp);  // before the file exists, so a signal never misses it
  errno = 0;
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    const int err = errno;
    staging::release(slot);
    return fail(path, "cannot create file: " + errno_text(err));
  }
  errno = 0;
  bool ok = fill(f) && std::ferror(f) == 0;
  int err = errno;
  // fclose flushes, so a full disk may only show up here.
  errno = 0;
  if (std::fclose(f) != 0 && ok) {
    ok = false;
    err = errno;
  }
  if (!ok) {
    std::remove(tmp.c_str());
    staging::release(slot);
    return fail(path, "cannot write: " + errno_text(err));
  }
  return StagedFile{tmp, path, slot};
}

Status publish_staged(Expected<StagedFile> staged) {
  if (!staged) return staged.error();
  return publish(*staged);
}

bool write_bytes(std::FILE* f, const void* data, std::size_t n) {
  return std::fwrite(data, 1, n, f) == n;
}

Status check_writable_size(const std::string& path, int width, int height) {
  if (width <= 0 || height <= 0) return fail(path, "cannot write an empty image");
  if (width > kMaxImageSide || height > kMaxImageSide) {
    return fail(path, "image too large to write (" + std::to_string(width) + " x " +
                          std::to_string(height) + ")");
  }
  return {};
}

}  // namespace

Status publish(const StagedFile& file) {
  errno = 0;
  if (std::rename(file.temp.c_str(), file.target.c_str()) != 0) {
    const int err = errno;
    std::remove(file.temp.c_str());
    staging::release(file.slot);
    return fail(file.target, "cannot rename temporary file into place: " + errno_text(err));
  }
  staging::release(file.slot);
  return {};
}

void discard(const StagedFile& file) {
  std::remove(file.temp.c_str());
  staging::release(file.slot);
}

Status write_all(const std::vector<std::string>& paths,
                 const std::function<Expected<StagedFile>(std::size_t)>& stage) {
  // Targets that cannot be renamed onto are refused before anything is written.
  for (const std::string& path : paths)
    if (Status s = check_output(path); !s) return s;
  std::vector<StagedFile> staged;
  auto discard_from = [&](std::size_t first) {
    for (std::size_t i = first; i < staged.size(); ++i) discard(staged[i]);
  };
  for (std::size_t i = 0; i < paths.size(); ++i) {
    Expected<StagedFile> f = stage(i);
    if (!f) {
      discard_from(0);
      return f.error();
    }
    staged.push_back(*f);
  }
  for (std::size_t i = 0; i < staged.size(); ++i) {
    if (Status s = publish(staged[i]); !s) {
      discard_from(i + 1);
      return s;
    }
  }
  return {};
}

Expected<RawImage> read_image(const std::string& path, int expect_width, int expect_height,
                              std::uint64_t max_bytes) {
  const std::string ext = lowercase_extension(path);
  const Expect e{expect_width, expect_height, max_bytes};
  if (ext == ".png") return read_png(path, e);
  if (ext == ".exr") return read_exr(path, e);
  if (ext == ".pfm") return read_pfm(path, e);
  return fail(path, "unsupported image format '" + ext + "' (supported: .png, .exr, .pfm)");
}

float srgb_to_linear(float v) {
  if (!(v > 0)) return 0;  // also maps NaN to 0
  if (v >= 1) return 1;
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float v) {
  if (!(v > 0)) return 0;
  if (v >= 1) return 1;
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

Expected<StagedFile> stage_pfm(const std::string& path, const ImageRgb& image) {
  if (Status s = check_writable_size(path, image.width(), image.height()); !s) return s.error();
  const int w = image.width(), h = image.height();
  const std::string header = "PF\n" + std::to_string(w) + " " + std::to_string(h) + "\n-1.0\n";
  return stage(path, [&](std::FILE* f) {
    if (!write_bytes(f, header.data(), header.size())) return false;
    const std::size_t row = std::size_t(w) * 3;
    std::vector<std::uint32_t> swapped;
    for (int y = h - 1; y >= 0; --y) {  // bottom row first
      const float* src = image.data() + std::size_t(y) * row;
      if constexpr (std::endian::native == std::endian::little) {
        if (!write_bytes(f, src, row * sizeof(float))) return false;
      } else {
        swapped.resize(row);
        for (std::size_t i = 0; i < row; ++i) {
          swapped[i] = byteswap32(std::bit_cast<std::uint32_t>(src[i]));
        }
        if (!write_bytes(f, swapped.data(), row * sizeof(float))) return false;
      }
    }
    return true;
  });
}

Expected<StagedFile> stage_exr(const std::string& path, const ImageRgb& image,
                               const std::string& world) {
  if (Status s = check_writable_size(path, image.width(), image.height()); !s) return s.error();
  const int w = image.width(), h = image.height();
  MemoryOStream out(path.c_str());
  try {
    Imf::Header header(w, h);
    header.compression() = Imf::ZIP_COMPRESSION;
    if (!world.empty()) header.insert("penumbra", Imf::StringAttribute(world));
    for (const char* name : {"R", "G", "B"})
      header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    Imf::FrameBuffer fb;
    // OpenEXR's Slice wants a non-const pointer even for writing; it only reads through it.
    char* base = reinterpret_cast<char*>(const_cast<float*>(image.data()));
    const std::size_t xs = 3 * sizeof(float), ys = xs * w;
    fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
    Imf::OutputFile file(out, header);  // its destructor writes the line offset table
    file.setFrameBuffer(fb);
    file.writePixels(h);
  } catch (const std::exception& e) {
    return fail(path, std::string("cannot encode EXR: ") + e.what());
  } catch (...) {
    return fail(path, "cannot encode EXR: unknown error");
  }
  return stage(
      path, [&](std::FILE* f) { return write_bytes(f, out.bytes().data(), out.bytes().size()); });
}

const std::string* ExrChannels::attribute(const std::string& name) const {
  for (const auto& [key, value] : attributes)
    if (key == name) return &value;
  return nullptr;
}

const ExrChannel* ExrChannels::channel(const std::string& name) const {
  for (const ExrChannel& c : channels)
    if (c.name == name) return &c;
  return nullptr;
}

Expected<StagedFile> stage_exr_channels(const std::string& path, const ExrChannels& image) {
  if (Status s = check_writable_size(path, image.width, image.height); !s) return s.error();
  const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
  if (image.channels.empty()) return fail(path, "cannot write an EXR without channels");
  for (const ExrChannel& c : image.channels)
    if (c.values.size() != n)
      return fail(path, "channel '" + c.name + "' holds " + std::to_string(c.values.size()) +
                            " values, expected " + std::to_string(n));
  MemoryOStream out(path.c_str());
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const auto& [key, value] : image.attributes)
      header.insert(key, Imf::StringAttribute(value));
    Imf::FrameBuffer fb;
    // OpenEXR writes a channel from a slice of its own type: half channels from a converted copy.
    std::vector<std::vector<half>> halves;
    for (const ExrChannel& c : image.channels)
      if (c.half) halves.emplace_back(c.values.begin(), c.values.end());
    std::size_t next_half = 0;
    for (const ExrChannel& c : image.channels) {
      header.channels().insert(c.name, Imf::Channel(c.half ? Imf::HALF : Imf::FLOAT));
      if (c.half) {
        char* base = reinterpret_cast<char*>(halves[next_half++].data());
        fb.insert(c.name, Imf::Slice(Imf::HALF, base, sizeof(half),
                                     sizeof(half) * std::size_t(image.width)));
        continue;
      }
      char* base = reinterpret_cast<char*>(const_cast<float*>(c.values.data()));
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, base, sizeof(float),
                                   sizeof(float) * std::size_t(image.width)));
    }
    Imf::OutputFile file(out, header);
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    return fail(path, std::string("cannot encode EXR: ") + e.what());
  } catch (...) {
    return fail(path, "cannot encode EXR: unknown error");
  }
  return stage(
      path, [&](std::FILE* f) { return write_bytes(f, out.bytes().data(), out.bytes().size()); });
}

Expected<ExrChannels> read_exr_channels(
    const std::string& path, std::uint64_t max_bytes,
    const std::function<bool(const std::string&)>& want,
    const std::function<Status(const ExrChannels&)>& check_header) {
  if (auto f = open_for_reading(path); !f) return f.error();
  try {
    if (Status s = check_exr_header(path, {}); !s) return s.error();
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const long long width = box_width(dw), height = box_height(dw);
    if (Status s = check_size(path, width, height, {}); !s) return s.error();
    ExrChannels img;
    img.width = int(width);
    img.height = int(height);
    for (auto it = file.header().begin(); it != file.header().end(); ++it)
      if (const auto* a = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
        img.attributes.emplace_back(it.name(), a->value());
    if (check_header)
      if (Status s = check_header(img); !s) return s.error();
    const Imf::ChannelList& list = file.header().channels();
    std::size_t count = 0;
    for (auto it = list.begin(); it != list.end(); ++it) {
      if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
        return fail(path, "subsampled channel '" + std::string(it.name()) + "' is not supported");
      if (!want || want(it.name())) ++count;
    }
    const double bytes = double(width) * double(height) * double(count) * sizeof(float);
    if (max_bytes > 0 && bytes > double(max_bytes))
      return fail(path, "reading its " + std::to_string(count) + " channels of " +
                            std::to_string(width) + "x" + std::to_string(height) + " takes " +
                            format_mib(std::uint64_t(bytes)) + ", more than the memory limit of " +
                            format_mib(max_bytes));
    if (!file.isComplete()) return fail(path, "truncated or damaged EXR (pixel data missing)");

    Imf::FrameBuffer fb;
    img.channels.reserve(count);
    for (auto it = list.begin(); it != list.end(); ++it) {
      if (want && !want(it.name())) continue;
      ExrChannel& c = img.channels.emplace_back();
      c.name = it.name();
      c.half = it.channel().type == Imf::HALF;
      c.values.resize(std::size_t(width) * std::size_t(height));
      fb.insert(c.name, Imf::Slice::Make(Imf::FLOAT, c.values.data(), dw, sizeof(float),
                                         sizeof(float) * std::size_t(width)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return img;
  } catch (const std::exception& e) {
    return fail(path, std::string("cannot read EXR: ") + e.what());
  } catch (...) {
    return fail(path, "cannot read EXR: unknown error");
  }
}

Expected<StagedFile> stage_png8(const std::string& path, int width, int height,
                                const std::vector<unsigned char>& rgb) {
  if (Status s = check_writable_size(path, width, height); !s) return s.error();
  if (rgb.size() != std::size_t(width) * height * 3) {
    return fail(path, "pixel buffer holds " + std::to_string(rgb.size()) + " bytes, expected " +
                          std::to_string(std::size_t(width) * height * 3));
  }
  std::vector<unsigned char> encoded;
  auto sink = [](void* ctx, void* data, int size) {
    auto* v = static_cast<std::vector<unsigned char>*>(ctx);
    const auto* p = static_cast<const unsigned char*>(data);
    v->insert(v->end(), p, p + size);
  };
  if (!stbi_write_png_to_func(sink, &encoded, width, height, 3, rgb.data(), width * 3)) {
    return fail(path, "cannot encode PNG");
  }
  return stage(path, [&](std::FILE* f) { return write_bytes(f, encoded.data(), encoded.size()); });
}

namespace {

// libpng reports errors by longjmp; this frame holds nothing with a destructor.
bool encode_png16(std::vector<unsigned char>& out, int width, int height, int channels,
                  const std::uint16_t* codes) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_set_write_fn(
      png, &out,
      [](png_structp p, png_bytep data, png_size_t size) {
        auto* v = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(p));
        v->insert(v->end(), data, data + size);
      },
      nullptr);
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 16,
               channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_set_swap(png);  // PNG stores 16-bit samples big-endian
  const std::size_t row = std::size_t(width) * channels;
  for (int y = 0; y < height; ++y)
    png_write_row(png, reinterpret_cast<png_const_bytep>(codes + row * std::size_t(y)));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

Expected<StagedFile> stage_png16(const std::string& path, int width, int height, int channels,
                                 const std::vector<std::uint16_t>& codes) {
  if (Status s = check_writable_size(path, width, height); !s) return s.error();
  if ((channels != 1 && channels != 3) ||
      codes.size() != std::size_t(width) * height * std::size_t(channels)) {
    return fail(path, "16-bit pixel buffer holds " + std::to_string(codes.size()) + " values for " +
                          std::to_string(channels) + " channels of " + std::to_string(width) +
                          " x " + std::to_string(height));
  }
  std::vector<unsigned char> encoded;
  if (!encode_png16(encoded, width, height, channels, codes.data()))
    return fail(path, "cannot encode PNG");
  return stage(path, [&](std::FILE* f) { return write_bytes(f, encoded.data(), encoded.size()); });
}

std::string image_world(const std::string& path) {
  if (lowercase_extension(path) != ".exr") return "";
  try {
    Imf::InputFile file(path.c_str());
    const auto* a = file.header().findTypedAttribute<Imf::StringAttribute>("penumbra");
    return a ? a->value() : "";
  } catch (...) {
    return "";
  }
}

Status write_pfm(const std::string& path, const ImageRgb& image) {
  return publish_staged(stage_pfm(path, image));
}

Status write_exr(const std::string& path, const ImageRgb& image) {
  return publish_staged(stage_exr(path, image));
}

Status write_png8(const std::string& path, int width, int height,
                  const std::vector<unsigned char>& rgb) {
  return publish_staged(stage_png8(path, width, height, rgb));
}

Expected<StagedFile> stage_text(const std::string& path, const std::string& text) {
  return stage(path, [&](std::FILE* f) {
    return std::fwrite(text.data(), 1, text.size(), f) == text.size();
  });
}

void remove_staged_and_die(int sig) {
  staging::remove_staged_and_die(sig);
}

Expected<std::string> read_text(const std::string& path, const std::string& what) {
  const std::string fail = path + ": cannot read " + what + ": ";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return Error{fail + "no such file"};
  if (std::filesystem::is_directory(path, ec)) return Error{fail + "it is a directory"};
  // A device or a pipe (/dev/zero, /dev/urandom) might never end; scenes are read twice anyway
  // (their dimensions, then the document).
  if (!std::filesystem::is_regular_file(path, ec)) return Error{fail + "not a regular file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{fail + "cannot open it"};
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return Error{fail + "read error"};
  return text;
}

Status write_text_files(const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<std::string> paths;
  for (const auto& [path, text] : files) paths.push_back(path);
  return write_all(paths,
                   [&](std::size_t i) { return stage_text(files[i].first, files[i].second); });
}

}  // namespace penumbra::io
