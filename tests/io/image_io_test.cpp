// Image I/O: round trips, exact bytes on disk, the display transform, and every error path.
#include "io/image_io.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "core/math.hpp"
#include "penumbra/flatland/io.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/io.hpp"
#include "test_support.hpp"

namespace penumbra::flatland {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<unsigned char>;

constexpr float kTwoPiF = float(kTwoPi);

class ImageIo : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return dir_.file(name); }
  // Every entry left in the test directory, to catch stray temporary files.
  std::vector<std::string> entries() const { return dir_.entries(); }

  testing::TestDir dir_{"image_io"};
};

Bytes read_bytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string& p, const Bytes& b) {
  std::ofstream out(p, std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

Bytes bytes_of(const std::string& s) {
  return Bytes(s.begin(), s.end());
}

void append(Bytes& b, const Bytes& more) {
  b.insert(b.end(), more.begin(), more.end());
}

bool starts_with(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// A test image whose values half floats could not hold, so precision loss would show.
ImageRgb awkward_image(int w, int h) {
  ImageRgb img(w, h);
  for (std::size_t i = 0; i < img.size(); ++i) {
    const float s = (i % 2 ? -1.0f : 1.0f);
    img.data()[i] = s * (float(i) / 3.0f + 1e-7f * float(i)) + (i == 5 ? 65536.5f : 0.0f);
  }
  img.data()[1] = 1e-40f;  // a denormal
  return img;
}

Scene empty_scene(int w, int h) {
  Scene s;
  s.width = w;
  s.height = h;
  s.emission.assign(s.cells() * 3, 0.0f);
  s.opacity.assign(s.cells(), 0.0f);
  s.albedo.assign(s.cells() * 3, 0.0f);
  return s;
}

ImageRgb uniform(int w, int h, float v) {
  ImageRgb img(w, h);
  for (std::size_t i = 0; i < img.size(); ++i) img.data()[i] = v;
  return img;
}

// 8-bit values of a PNG as read back (read_image scales them by 1/255).
std::vector<int> png_bytes(const std::string& p) {
  auto img = io::read_image(p);
  EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.error().message);
  std::vector<int> out;
  if (!img.ok()) return out;
  for (float v : img->pixels) out.push_back(int(std::lround(v * 255.0f)));
  return out;
}

// ---- A minimal PNG encoder (stored deflate blocks), independent of stb ----

std::uint32_t crc32(const Bytes& b, std::size_t from) {
  std::uint32_t c = 0xffffffffu;
  for (std::size_t i = from; i < b.size(); ++i) {
    c ^= b[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return ~c;
}

void put32(Bytes& b, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back((unsigned char)(v >> s));
}

void chunk(Bytes& png, const char* type, const Bytes& data) {
  put32(png, std::uint32_t(data.size()));
  const std::size_t start = png.size();
  png.insert(png.end(), type, type + 4);
  append(png, data);
  put32(png, crc32(png, start));
}

// `rows` holds the raw scanlines without filter bytes; one stored deflate block.
Bytes make_png(int w, int h, int depth, int colour_type, const Bytes& rows) {
  Bytes raw;
  const std::size_t stride = rows.size() / h;
  for (int y = 0; y < h; ++y) {
    raw.push_back(0);  // filter: none
    raw.insert(raw.end(), rows.begin() + y * stride, rows.begin() + (y + 1) * stride);
  }
  Bytes z = {0x78, 0x01, 0x01};  // zlib header, final stored block
  const auto n = std::uint16_t(raw.size());
  z.insert(z.end(), {(unsigned char)(n & 0xff), (unsigned char)(n >> 8), (unsigned char)(~n & 0xff),
                     (unsigned char)((~n >> 8) & 0xff)});
  append(z, raw);
  std::uint32_t a = 1, bsum = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521;
    bsum = (bsum + a) % 65521;
  }
  put32(z, (bsum << 16) | a);

  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Bytes ihdr;
  put32(ihdr, std::uint32_t(w));
  put32(ihdr, std::uint32_t(h));
  ihdr.insert(ihdr.end(), {(unsigned char)depth, (unsigned char)colour_type, 0, 0, 0});
  chunk(png, "IHDR", ihdr);
  chunk(png, "IDAT", z);
  chunk(png, "IEND", {});
  return png;
}

// ---- PFM ----

TEST_F(ImageIo, PfmRoundTripIsBitIdentical) {
  const ImageRgb img = awkward_image(5, 3);
  const std::string p = path("a.pfm");
  ASSERT_TRUE(io::write_pfm(p, img).ok());
  auto back = io::read_image(p);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->width, 5);
  EXPECT_EQ(back->height, 3);
  EXPECT_EQ(back->channels, 3);
  EXPECT_FALSE(back->integer_png);
  ASSERT_EQ(back->pixels.size(), img.size());
  EXPECT_EQ(std::memcmp(back->pixels.data(), img.data(), img.size() * sizeof(float)), 0);

  auto rgb = read_rgb_image(p);
  ASSERT_TRUE(rgb.ok());
  EXPECT_EQ(std::memcmp(rgb->data(), img.data(), img.size() * sizeof(float)), 0);
  EXPECT_EQ(entries(), std::vector<std::string>{"a.pfm"});
}

TEST_F(ImageIo, PfmBytesMatchHandBuiltFile) {
  ImageRgb img(2, 2);
  img.set(0, 0, {1.0f, 2.0f, 0.5f});
  img.set(1, 0, {-1.0f, 0.0f, 1.0f});
  img.set(0, 1, {2.0f, 0.0f, 0.0f});
  img.set(1, 1, {0.5f, -1.0f, 2.0f});
  const std::string p = path("tiny.pfm");
  ASSERT_TRUE(io::write_pfm(p, img).ok());

  // IEEE-754 little-endian: 1 = 3f800000, 2 = 40000000, 0.5 = 3f000000, -1 = bf800000.
  const Bytes one = {0, 0, 0x80, 0x3f}, two = {0, 0, 0, 0x40}, half = {0, 0, 0, 0x3f},
              minus_one = {0, 0, 0x80, 0xbf}, zero = {0, 0, 0, 0};
  Bytes expected = bytes_of("PF\n2 2\n-1.0\n");
  for (const Bytes* v : {&two, &zero, &zero, &half, &minus_one, &two,  // bottom row (y = 1) first
                         &one, &two, &half, &minus_one, &zero, &one}) {
    append(expected, *v);
  }
  EXPECT_EQ(read_bytes(p), expected);
}

TEST_F(ImageIo, PfmReadsGreyBigEndianBottomRowFirst) {
  // 1 x 2 grey, positive scale = big-endian; the bottom row (1.0) is stored first.
  Bytes file = bytes_of("Pf\n1 2\n1.0\n");
  append(file, {0x3f, 0x80, 0, 0});  // 1.0, bottom
  append(file, {0x40, 0, 0, 0});     // 2.0, top
  const std::string p = path("grey.pfm");
  write_bytes(p, file);
  auto img = io::read_image(p);
  ASSERT_TRUE(img.ok()) << img.error().message;
  EXPECT_EQ(img->channels, 1);
  EXPECT_EQ(img->width, 1);
  EXPECT_EQ(img->height, 2);
  EXPECT_EQ(img->pixels, (std::vector<float>{2.0f, 1.0f}));

  auto rgb = read_rgb_image(p);
  ASSERT_TRUE(rgb.ok());
  EXPECT_EQ(rgb->at(0, 0).g, 2.0f);
  EXPECT_EQ(rgb->at(0, 0).b, 2.0f);
  EXPECT_EQ(rgb->at(0, 1).r, 1.0f);
}

TEST_F(ImageIo, PfmWithUpperCaseExtensionReads) {
  const std::string p = path("LOUD.PFM");
  ASSERT_TRUE(io::write_pfm(p, uniform(1, 1, 0.25f)).ok());
  auto img = io::read_image(p);
  ASSERT_TRUE(img.ok()) << img.error().message;
  EXPECT_EQ(img->pixels, (std::vector<float>{0.25f, 0.25f, 0.25f}));
}

TEST_F(ImageIo, WriteReplacesAnExistingFile) {
  const std::string p = path("again.pfm");
  ASSERT_TRUE(io::write_pfm(p, uniform(3, 3, 1.0f)).ok());
  ASSERT_TRUE(io::write_pfm(p, uniform(1, 1, 7.0f)).ok());
  auto img = io::read_image(p);
  ASSERT_TRUE(img.ok());
  EXPECT_EQ(img->pixels, (std::vector<float>{7.0f, 7.0f, 7.0f}));
  EXPECT_EQ(entries(), std::vector<std::string>{"again.pfm"});
}

// ---- EXR ----

TEST_F(ImageIo, ExrRoundTripIsBitIdentical) {
  const ImageRgb img = awkward_image(7, 4);
  const std::string p = path("a.exr");
  ASSERT_TRUE(io::write_exr(p, img).ok());
  auto back = io::read_image(p);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->width, 7);
  EXPECT_EQ(back->height, 4);
  EXPECT_EQ(back->channels, 3);
  ASSERT_EQ(back->pixels.size(), img.size());
  EXPECT_EQ(std::memcmp(back->pixels.data(), img.data(), img.size() * sizeof(float)), 0);
  EXPECT_EQ(entries(), std::vector<std::string>{"a.exr"});
}

TEST_F(ImageIo, ExrReadsDataWindowAndSingleChannel) {
  // Written by OpenEXR 3.1 itself: uncompressed FLOAT channel "Y", display window
  // (0,0)-(9,9), data window (5,7)-(7,8), rows {1,2,3} and {4,5,6}.
  static const char kFile[] =
      "\x76\x2f\x31\x01\x02\x00\x00\x00\x63\x68\x61\x6e\x6e\x65\x6c\x73\x00\x63\x68\x6c\x69\x73"
      "\x74\x00\x13\x00\x00\x00\x59\x00\x02\x00\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x01\x00"
      "\x00\x00\x00\x63\x6f\x6d\x70\x72\x65\x73\x73\x69\x6f\x6e\x00\x63\x6f\x6d\x70\x72\x65\x73"
      "\x73\x69\x6f\x6e\x00\x01\x00\x00\x00\x00\x64\x61\x74\x61\x57\x69\x6e\x64\x6f\x77\x00\x62"
      "\x6f\x78\x32\x69\x00\x10\x00\x00\x00\x05\x00\x00\x00\x07\x00\x00\x00\x07\x00\x00\x00\x08"
      "\x00\x00\x00\x64\x69\x73\x70\x6c\x61\x79\x57\x69\x6e\x64\x6f\x77\x00\x62\x6f\x78\x32\x69"
      "\x00\x10\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x09\x00\x00\x00\x09\x00\x00\x00\x6c"
      "\x69\x6e\x65\x4f\x72\x64\x65\x72\x00\x6c\x69\x6e\x65\x4f\x72\x64\x65\x72\x00\x01\x00\x00"
      "\x00\x00\x70\x69\x78\x65\x6c\x41\x73\x70\x65\x63\x74\x52\x61\x74\x69\x6f\x00\x66\x6c\x6f"
      "\x61\x74\x00\x04\x00\x00\x00\x00\x00\x80\x3f\x73\x63\x72\x65\x65\x6e\x57\x69\x6e\x64\x6f"
      "\x77\x43\x65\x6e\x74\x65\x72\x00\x76\x32\x66\x00\x08\x00\x00\x00\x00\x00\x00\x00\x00\x00"
      "\x00\x00\x73\x63\x72\x65\x65\x6e\x57\x69\x6e\x64\x6f\x77\x57\x69\x64\x74\x68\x00\x66\x6c"
      "\x6f\x61\x74\x00\x04\x00\x00\x00\x00\x00\x80\x3f\x00\x25\x01\x00\x00\x00\x00\x00\x00\x39"
      "\x01\x00\x00\x00\x00\x00\x00\x07\x00\x00\x00\x0c\x00\x00\x00\x00\x00\x80\x3f\x00\x00\x00"
      "\x40\x00\x00\x40\x40\x08\x00\x00\x00\x0c\x00\x00\x00\x00\x00\x80\x40\x00\x00\xa0\x40\x00"
      "\x00\xc0\x40";
  const std::string p = path("window.exr");
  write_bytes(p, Bytes(kFile, kFile + sizeof kFile - 1));
  auto img = io::read_image(p);
  ASSERT_TRUE(img.ok()) << img.error().message;
  EXPECT_EQ(img->width, 3);
  EXPECT_EQ(img->height, 2);
  EXPECT_EQ(img->channels, 1);
  EXPECT_EQ(img->pixels, (std::vector<float>{1, 2, 3, 4, 5, 6}));
}

TEST_F(ImageIo, TruncatedOrGarbageExrIsAnError) {
  const std::string good = path("good.exr");
  ASSERT_TRUE(io::write_exr(good, awkward_image(16, 16)).ok());
  Bytes b = read_bytes(good);
  b.resize(b.size() / 2);
  const std::string cut = path("cut.exr");
  write_bytes(cut, b);
  auto r = io::read_image(cut);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(starts_with(r.error().message, cut + ": ")) << r.error().message;

  const std::string junk = path("junk.exr");
  write_bytes(junk, bytes_of("this is not an EXR file at all"));
  auto j = io::read_image(junk);
  ASSERT_FALSE(j.ok());
  EXPECT_TRUE(starts_with(j.error().message, junk + ": ")) << j.error().message;
}

// ---- PNG ----

// An 8x8 EXR whose header claims 16384^2, padded so that OpenEXR opens it: refused before its
// pixels (3 GiB of floats) are allocated. Found by fuzzing the readers (docs/RELIABILITY.md).
TEST_F(ImageIo, ExrClaimingAHugeSizeIsRefusedBeforeAllocating) {
  const std::string p = path("huge.exr");
  ASSERT_TRUE(io::write_exr(p, awkward_image(8, 8)).ok());
  Bytes b = read_bytes(p);
  for (const std::string name : {"dataWindow", "displayWindow"}) {
    const std::string key = name + std::string("\0box2i\0", 7);
    auto at = std::search(b.begin(), b.end(), key.begin(), key.end());
    ASSERT_NE(at, b.end()) << name;
    // After the name and type: the attribute's size (4 bytes), then xmin, ymin, xmax, ymax.
    const std::size_t off = std::size_t(at - b.begin()) + key.size() + 4;
    const std::int32_t box[4] = {0, 0, 16383, 16383};
    std::memcpy(b.data() + off, box, sizeof box);
  }
  b.resize(b.size() + 9000, 0);  // room for the 1024 offsets of 16384 lines
  write_bytes(p, b);
  auto r = io::read_image(p);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, p + ": truncated or damaged EXR (pixel data missing)");
}

// An EXR whose data window is wider than the limit: refused from the header read alone, before
// OpenEXR opens the file and sizes its line buffers for 131072 columns. Found by the image
// fuzzer (docs/RELIABILITY.md).
TEST_F(ImageIo, ExrWiderThanTheLimitIsRefusedFromItsHeader) {
  const std::string p = path("wide.exr");
  ASSERT_TRUE(io::write_exr(p, awkward_image(8, 8)).ok());
  Bytes b = read_bytes(p);
  const std::string key("dataWindow\0box2i\0", 17);
  auto at = std::search(b.begin(), b.end(), key.begin(), key.end());
  ASSERT_NE(at, b.end());
  const std::int32_t box[4] = {0, 0, 131071, 7};
  std::memcpy(b.data() + (at - b.begin()) + key.size() + 4, box, sizeof box);
  write_bytes(p, b);
  auto r = io::read_image(p);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, p + ": image too large (131072 x 8, the limit is 16384 per side)");
}

// An EXR whose version field has every flag set is an error, read without overflowing (the
// header check once assembled the field in a signed int: UBSan, found by the image fuzzer).
TEST_F(ImageIo, ExrWithEveryVersionFlagIsAnError) {
  const std::string p = path("flags.exr");
  ASSERT_TRUE(io::write_exr(p, awkward_image(8, 8)).ok());
  Bytes b = read_bytes(p);
  for (int i = 4; i < 8; ++i) b[i] = 0xff;
  write_bytes(p, b);
  auto r = io::read_image(p);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(starts_with(r.error().message, p + ": ")) << r.error().message;
}

// A 69-byte PNG whose header claims 16384^2 pixels: refused from its header, before stb sizes
// its buffers from it (16-bit RGBA overflowed stb's int sizes; 8-bit RGB would allocate 768 MiB
// before finding the data short). Found by fuzzing the readers (docs/RELIABILITY.md).
TEST_F(ImageIo, PngClaimingAHugeSizeIsRefusedFromItsHeader) {
  auto chunk = [](Bytes& png, const char* type, const Bytes& data) {
    auto be32 = [&](std::uint32_t v) {
      for (int s = 24; s >= 0; s -= 8) png.push_back(static_cast<unsigned char>(v >> s));
    };
    be32(static_cast<std::uint32_t>(data.size()));
    Bytes typed(type, type + 4);
    typed.insert(typed.end(), data.begin(), data.end());
    png.insert(png.end(), typed.begin(), typed.end());
    // The chunk's CRC-32 over its type and data.
    std::uint32_t crc = 0xffffffffu;
    for (unsigned char c : typed) {
      crc ^= c;
      for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    be32(crc ^ 0xffffffffu);
  };
  // zlib stream of 100 zero bytes.
  const Bytes idat = {0x78, 0x9c, 0x63, 0x60, 0xa0, 0x3d, 0x00, 0x00, 0x00, 0x64, 0x00, 0x01};
  const std::pair<int, const char*> cases[] = {{16 * 256 + 6, "PNG too large to decode"},
                                               {8 * 256 + 2, "truncated PNG"}};
  for (const auto& [depth_and_type, want] : cases) {
    Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    chunk(png, "IHDR",
          {0, 0, 0x40, 0, 0, 0, 0x40, 0, static_cast<unsigned char>(depth_and_type >> 8),
           static_cast<unsigned char>(depth_and_type & 0xff), 0, 0, 0});
    chunk(png, "IDAT", idat);
    chunk(png, "IEND", {});
    const std::string p = path("huge.png");
    write_bytes(p, png);
    auto r = io::read_image(p);
    ASSERT_FALSE(r.ok()) << want;
    EXPECT_TRUE(starts_with(r.error().message, p + ": " + want)) << r.error().message;
  }
}

// A PNG cut inside its IHDR chunk (25 bytes: the signature, the chunk's length and type, 9 of its
// 13 bytes): stb reads zeros past the end and accepts its header, so the size check read past
// the buffer. Found by fuzzing the readers (docs/RELIABILITY.md); every cut is refused.
TEST_F(ImageIo, PngCutInsideItsHeaderIsRefused) {
  const Bytes whole = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0,    0,    0,
                       13,   'I', 'H', 'D', 'R',  0,    0,    0,    8,    0,    0,
                       0,    8,   8,   2,   0,    0,    0,    0x4b, 0x6d, 0x29, 0xde};
  for (std::size_t n = 9; n < whole.size(); ++n) {
    const std::string p = path("cut.png");
    write_bytes(p, Bytes(whole.begin(), whole.begin() + std::ptrdiff_t(n)));
    auto r = io::read_image(p);
    ASSERT_FALSE(r.ok()) << n << " bytes";
    // Cut before byte 25 stb itself refuses it (malformed); from there on, the size check.
    EXPECT_TRUE(
        starts_with(r.error().message, p + (n < 25 ? ": malformed PNG" : ": truncated PNG (")))
        << r.error().message;
  }
}

// An EXR header whose preview claims a size whose byte count passes 64 bits (a signed overflow,
// undefined behaviour, before it was checked against the file). Found by fuzz_image in this
// form (docs/RELIABILITY.md); refused as a damaged header.
TEST_F(ImageIo, ExrPreviewOfAnImpossibleSizeIsRefused) {
  const std::string b64 =
      "di8xAQIAAABjaGFubmVscwBjaGxpc3QAAAcAAABsaW5lT3JkZXI/AHByZXZpZXcAAQAAAAB5cGl4ZWNvcHJldmll"
      "aW9uAGYSbG9hdABpwA==";
  const std::string table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  Bytes bytes;
  unsigned bits = 0;
  int have = 0;
  for (char c : b64) {
    if (c == '=') break;
    bits = (bits << 6) | unsigned(table.find(c));
    have += 6;
    if (have >= 8) {
      have -= 8;
      bytes.push_back(static_cast<unsigned char>((bits >> have) & 0xffu));
    }
  }
  const std::string p = path("preview.exr");
  write_bytes(p, bytes);
  auto r = io::read_image(p);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(starts_with(r.error().message, p + ": ")) << r.error().message;
}

TEST_F(ImageIo, Png8RoundTripKeepsValues) {
  const std::vector<unsigned char> rgb = {0,   1,   2,  127, 128, 129,  // row 0
                                          254, 255, 17, 200, 64,  3};   // row 1
  const std::string p = path("a.png");
  ASSERT_TRUE(io::write_png8(p, 2, 2, rgb).ok());
  auto img = io::read_image(p);
  ASSERT_TRUE(img.ok()) << img.error().message;
  EXPECT_EQ(img->width, 2);
  EXPECT_EQ(img->height, 2);
  EXPECT_EQ(img->channels, 3);
  EXPECT_TRUE(img->integer_png);
  EXPECT_EQ(png_bytes(p), std::vector<int>(rgb.begin(), rgb.end()));
  EXPECT_EQ(entries(), std::vector<std::string>{"a.png"});
}

TEST_F(ImageIo, Png16BitGreyIsScaledToUnit) {
  const std::string p = path("grey16.png");
  write_bytes(p, make_png(3, 1, 16, 0, {0x00, 0x00, 0x80, 0x00, 0xff, 0xff}));
  auto img = io::read_image(p);
  ASSERT_TRUE(img.ok()) << img.error().message;
  EXPECT_EQ(img->channels, 1);
  EXPECT_TRUE(img->integer_png);
  ASSERT_EQ(img->pixels.size(), 3u);
  EXPECT_EQ(img->pixels[0], 0.0f);
  EXPECT_FLOAT_EQ(img->pixels[1], 32768.0f / 65535.0f);
  EXPECT_EQ(img->pixels[2], 1.0f);
}

TEST_F(ImageIo, PngGreyAlphaKeepsChannelsAndDecodesToRgb) {
  // 2 x 1 grey + alpha, 8-bit: (128, 255), (255, 0).
  const std::string p = path("ga.png");
  write_bytes(p, make_png(2, 1, 8, 4, {128, 255, 255, 0}));
  auto img = io::read_image(p);
  ASSERT_TRUE(img.ok()) << img.error().message;
  EXPECT_EQ(img->channels, 2);
  EXPECT_EQ(png_bytes(p), (std::vector<int>{128, 255, 255, 0}));

  // read_rgb_image decodes sRGB and drops alpha: 128/255 -> 0.2158605 (sRGB curve).
  auto rgb = read_rgb_image(p);
  ASSERT_TRUE(rgb.ok());
  EXPECT_NEAR(rgb->at(0, 0).r, 0.2158605f, 1e-6f);
  EXPECT_NEAR(rgb->at(0, 0).b, 0.2158605f, 1e-6f);
  EXPECT_EQ(rgb->at(1, 0).g, 1.0f);
}

TEST_F(ImageIo, GarbagePngIsAnError) {
  const std::string p = path("junk.png");
  write_bytes(p, bytes_of("GIF89a and then nothing useful"));
  auto r = io::read_image(p);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(starts_with(r.error().message, p + ": ")) << r.error().message;

  // A valid signature with a cut-off body.
  Bytes b = make_png(4, 4, 8, 2, Bytes(48, 7));
  b.resize(40);
  write_bytes(p, b);
  auto c = io::read_image(p);
  ASSERT_FALSE(c.ok());
  EXPECT_TRUE(starts_with(c.error().message, p + ": ")) << c.error().message;
}

// ---- sRGB ----

TEST_F(ImageIo, SrgbCurvesAtKnownPoints) {
  EXPECT_EQ(io::srgb_to_linear(0.0f), 0.0f);
  EXPECT_EQ(io::srgb_to_linear(1.0f), 1.0f);
  EXPECT_NEAR(io::srgb_to_linear(0.5f), 0.2140411f, 1e-6f);
  EXPECT_NEAR(io::srgb_to_linear(0.04f), 0.04f / 12.92f, 1e-9f);  // linear segment
  EXPECT_EQ(io::linear_to_srgb(0.0f), 0.0f);
  EXPECT_EQ(io::linear_to_srgb(1.0f), 1.0f);
  EXPECT_NEAR(io::linear_to_srgb(0.5f), 0.7353570f, 1e-6f);
  EXPECT_NEAR(io::linear_to_srgb(0.002f), 0.002f * 12.92f, 1e-9f);
  // Inputs outside [0, 1] are clamped.
  EXPECT_EQ(io::srgb_to_linear(-0.5f), 0.0f);
  EXPECT_EQ(io::srgb_to_linear(3.0f), 1.0f);
  EXPECT_EQ(io::linear_to_srgb(-1.0f), 0.0f);
  EXPECT_EQ(io::linear_to_srgb(42.0f), 1.0f);
  for (int i = 0; i <= 100; ++i) {
    const float x = float(i) / 100.0f;
    EXPECT_NEAR(io::linear_to_srgb(io::srgb_to_linear(x)), x, 1e-5f) << x;
  }
}

// ---- write_image ----

// Expected bytes: ACES(x) = x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14), then sRGB, then x255.
// x = 0.18: ACES 0.2668989, sRGB 0.5534576, 141.13 -> 141.
// x = 1.0:  ACES 0.8037975, sRGB 0.9082305, 231.60 -> 232.
constexpr int kByteOf018 = 141;

// The display bytes of `f` (no scene) at `exposure`.
std::vector<unsigned char> png_bytes_of(const ImageRgb& f, float exposure) {
  return display_picture(f, nullptr, {.exposure = exposure}).rgb;
}
constexpr int kByteOf1 = 232;

TEST_F(ImageIo, WriteImagePngShowsToneMappedMeanRadiance) {
  const std::string p = path("grey.png");
  ASSERT_TRUE(write_image(p, uniform(3, 2, kTwoPiF * 0.18f), empty_scene(3, 2)).ok());
  EXPECT_EQ(png_bytes(p), std::vector<int>(18, kByteOf018));

  // Half the light and one stop of exposure look the same.
  const std::string q = path("exposed.png");
  ASSERT_TRUE(
      write_image(q, uniform(3, 2, kTwoPiF * 0.09f), empty_scene(3, 2), {.exposure = 1}).ok());
  EXPECT_EQ(png_bytes(q), std::vector<int>(18, kByteOf018));
}

TEST_F(ImageIo, WriteImagePngRowZeroIsTop) {
  ImageRgb f(1, 2);
  f.set(0, 0, {kTwoPiF, kTwoPiF, kTwoPiF});  // mean radiance 1
  f.set(0, 1, {0, 0, 0});
  const std::string p = path("rows.png");
  ASSERT_TRUE(write_image(p, f, empty_scene(1, 2)).ok());
  EXPECT_EQ(png_bytes(p), (std::vector<int>{kByteOf1, kByteOf1, kByteOf1, 0, 0, 0}));
}

TEST_F(ImageIo, WriteImagePngCompositesEmittersAndLitWalls) {
  Scene s = empty_scene(3, 1);
  // Cell 0: opaque emitter (1, 0, 0.18), black albedo.
  s.opacity[0] = 1;
  s.emission[0] = 1.0f;
  s.emission[2] = 0.18f;
  // Cell 1: opaque wall, albedo 0.5, lit by mean radiance 0.36: reflects 0.18.
  s.opacity[1] = 1;
  s.albedo[3] = s.albedo[4] = s.albedo[5] = 0.5f;
  ImageRgb f = uniform(3, 1, kTwoPiF * 0.18f);
  f.set(1, 0, {kTwoPiF * 0.36f, kTwoPiF * 0.36f, kTwoPiF * 0.36f});
  const std::string p = path("emit.png");
  ASSERT_TRUE(write_image(p, f, s).ok());
  EXPECT_EQ(png_bytes(p), (std::vector<int>{kByteOf1, 0, kByteOf018,                //
                                            kByteOf018, kByteOf018, kByteOf018,     //
                                            kByteOf018, kByteOf018, kByteOf018}));  // clear
}

// The automatic exposure meters the median lit open cell to kAutoExposureKey: a uniform field
// of mean radiance m gives exactly log2(key / m); opaque and emitting cells, and cells in full
// darkness, are not metered; the median, not the mean, so that a few bright cells do not move it.
TEST_F(ImageIo, AutoExposureMetersTheMedianLitOpenCell) {
  for (float m : {0.01f, 0.18f, 3.0f}) {
    const float ev = auto_exposure(uniform(4, 3, kTwoPiF * m), nullptr);
    EXPECT_NEAR(ev, std::log2(kAutoExposureKey / m), 1e-5f) << m;
    // Exposed so, the picture is the key grey everywhere.
    EXPECT_EQ(png_bytes_of(uniform(4, 3, kTwoPiF * m), ev),
              png_bytes_of(uniform(4, 3, kTwoPiF * kAutoExposureKey), 0));
  }
  Scene s = empty_scene(5, 1);
  ImageRgb f = uniform(5, 1, kTwoPiF * 0.5f);
  f.set(0, 0, {kTwoPiF * 100, kTwoPiF * 100, kTwoPiF * 100});  // an opaque wall: not metered
  s.opacity[0] = 1;
  f.set(1, 0, {kTwoPiF * 200, kTwoPiF * 200, kTwoPiF * 200});  // a glowing cell: not metered
  s.opacity[1] = 0.5f;
  s.emission[3] = 1;
  f.set(2, 0, {0, 0, 0});                                         // full darkness: not metered
  f.set(3, 0, {kTwoPiF * 1000, kTwoPiF * 1000, kTwoPiF * 1000});  // one bright open cell of two
  // The lit open cells: 1000 and 0.5; the median of two is the upper one.
  EXPECT_NEAR(auto_exposure(f, &s), std::log2(kAutoExposureKey / 1000.0f), 1e-5f);
  f.set(2, 0, {kTwoPiF * 0.4f, kTwoPiF * 0.4f, kTwoPiF * 0.4f});  // now 0.4, 0.5, 1000
  EXPECT_NEAR(auto_exposure(f, &s), std::log2(kAutoExposureKey / 0.5f), 1e-5f);
  // Nothing lit: no exposure.
  EXPECT_EQ(auto_exposure(uniform(3, 3, 0), nullptr), 0.0f);
}

// Walls and fog in the dark keep a dim floor of their albedo's colour when asked (the painter's
// default, `render --show-walls`); lit cells and emitters are left as they were.
TEST_F(ImageIo, ShowWallsLiftsOnlyDarkWallsAndFog) {
  Scene s = empty_scene(4, 1);
  s.opacity[0] = 1;  // a dark wall, albedo 1: floor 0.3 of white
  s.albedo[0] = s.albedo[1] = s.albedo[2] = 1;
  s.opacity[1] = 0.1f;  // thin fog, albedo 0: 0.25 of 0.3 * 0.5
  s.opacity[2] = 1;     // a dark emitter showing nothing: stays black
  s.emission[6] = 0;
  s.emission[7] = 1e-9f;
  ImageRgb f = uniform(4, 1, 0);
  f.set(3, 0, {kTwoPiF, kTwoPiF, kTwoPiF});  // a lit open cell
  const ImageRgb8 plain = display_picture(f, &s, {});
  const ImageRgb8 shown = display_picture(f, &s, {.exposure = 0, .show_walls = true});
  EXPECT_EQ(plain.rgb[0], 0);
  EXPECT_EQ(shown.rgb[0], static_cast<unsigned char>(255 * 0.3f));
  EXPECT_EQ(shown.rgb[3], static_cast<unsigned char>(255 * 0.3f * 0.5f * 0.25f));
  EXPECT_EQ(shown.rgb[6], 0);
  for (int c = 9; c < 12; ++c) EXPECT_EQ(shown.rgb[std::size_t(c)], plain.rgb[std::size_t(c)]);
}

TEST_F(ImageIo, WriteImageLinearFormatsKeepFluence) {
  const ImageRgb img = awkward_image(4, 3);
  const Scene s = empty_scene(4, 3);
  for (const char* name : {"out.pfm", "out.exr", "OUT.EXR"}) {
    const std::string p = path(name);
    ASSERT_TRUE(write_image(p, img, s).ok()) << name;
    auto back = read_rgb_image(p);
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(std::memcmp(back->data(), img.data(), img.size() * sizeof(float)), 0) << name;
  }
}

TEST_F(ImageIo, SupportedOutputs) {
  EXPECT_TRUE(is_supported_output("a.pfm"));
  EXPECT_TRUE(is_supported_output("dir.x/a.EXR"));
  EXPECT_TRUE(is_supported_output("a.Png"));
  EXPECT_FALSE(is_supported_output("a.jpg"));
  EXPECT_FALSE(is_supported_output("png"));
  EXPECT_FALSE(is_supported_output("a.png.bak"));
}

// ---- Errors ----

TEST_F(ImageIo, MissingFileIsAnError) {
  for (const char* name : {"none.pfm", "none.exr", "none.png"}) {
    const std::string p = path(name);
    auto r = io::read_image(p);
    ASSERT_FALSE(r.ok()) << name;
    EXPECT_TRUE(starts_with(r.error().message, p + ": ")) << r.error().message;
    EXPECT_NE(r.error().message.find("No such file"), std::string::npos) << r.error().message;
    EXPECT_FALSE(read_rgb_image(p).ok());
  }
}

TEST_F(ImageIo, TruncatedPfmIsAnError) {
  Bytes file = bytes_of("PF\n16 16\n-1.0\n");
  append(file, Bytes(100, 0));
  const std::string p = path("short.pfm");
  write_bytes(p, file);
  auto r = io::read_image(p);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, p + ": truncated data (expected 3072 bytes, found 100)");
}

TEST_F(ImageIo, BadPfmHeaderIsAnError) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"P6\n2 2\n255\n", "bad PFM header"},
      {"PF\n2 x\n-1.0\n", "bad PFM header"},
      {"PF\n2 2\n0\n", "bad PFM header"},
      {"PF\n2 2\nnan\n", "bad PFM header"},
      {"PF\n-2 2\n-1.0\n", "zero size"},
      {"PF\n0 2\n-1.0\n", "zero size"},
      {"PF\n16385 1\n-1.0\n", "too large"},
      {"PF\n2 2", "bad PFM header"},
      {"", "bad PFM header"},
      {"PF\n2 2.5\n-1.0\n", "bad PFM header"},
  };
  const std::string p = path("bad.pfm");
  for (const auto& [text, want] : cases) {
    write_bytes(p, bytes_of(text));
    auto r = io::read_image(p);
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_TRUE(starts_with(r.error().message, p + ": ")) << r.error().message;
    EXPECT_NE(r.error().message.find(want), std::string::npos) << r.error().message;
  }
}

TEST_F(ImageIo, UnknownExtensionIsAnError) {
  const std::string bmp = path("picture.bmp");
  write_bytes(bmp, bytes_of("BM"));
  auto r = io::read_image(bmp);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(starts_with(r.error().message, bmp + ": ")) << r.error().message;

  const std::string tiff = path("out.tiff");
  Status s = write_image(tiff, uniform(2, 2, 1), empty_scene(2, 2));
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(starts_with(s.error().message, tiff + ": ")) << s.error().message;
  for (const char* ext : {".pfm", ".exr", ".png"}) {
    EXPECT_NE(s.error().message.find(ext), std::string::npos) << s.error().message;
  }
  EXPECT_FALSE(fs::exists(tiff));
}

TEST_F(ImageIo, WriteIntoMissingDirectoryLeavesNothing) {
  const Scene scene = empty_scene(2, 2);
  for (const char* name : {"a.pfm", "a.exr", "a.png"}) {
    const std::string p = path("no/such/dir/") + name;
    Status s = write_image(p, uniform(2, 2, 1), scene);
    ASSERT_FALSE(s.ok()) << name;
    EXPECT_TRUE(starts_with(s.error().message, p + ": ")) << s.error().message;
    EXPECT_NE(s.error().message.find("No such file or directory"), std::string::npos)
        << s.error().message;
  }
  EXPECT_FALSE(fs::exists(path("no")));
  EXPECT_TRUE(entries().empty());
}

TEST_F(ImageIo, FailedRenameRemovesTemporaryFile) {
  // The target is a non-empty directory: the temporary file is written, the rename fails.
  const Scene scene = empty_scene(2, 2);
  for (const char* name : {"d.pfm", "d.exr", "d.png"}) {
    const std::string p = path(name);
    fs::create_directory(p);
    write_bytes(p + "/keep", bytes_of("x"));
    Status s = write_image(p, uniform(2, 2, 1), scene);
    ASSERT_FALSE(s.ok()) << name;
    EXPECT_TRUE(starts_with(s.error().message, p + ": ")) << s.error().message;
    EXPECT_TRUE(fs::is_directory(p));
  }
  auto names = entries();
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"d.exr", "d.pfm", "d.png"}));
}

TEST_F(ImageIo, FluenceSceneSizeMismatchIsAnError) {
  const std::string p = path("mismatch.png");
  Status s = write_image(p, uniform(4, 3, 1), empty_scene(3, 4));
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(starts_with(s.error().message, p + ": ")) << s.error().message;
  EXPECT_TRUE(entries().empty());
}

// Several outputs are written all or nothing: a later one that fails leaves no earlier one (and
// no temporary file) behind.
TEST_F(ImageIo, WriteImagesIsAllOrNothing) {
  const ImageRgb f = uniform(4, 3, 1);
  const Scene sc = empty_scene(4, 3);
  Status s = write_images({path("a.pfm"), path("b.exr"), path("c.bmp")}, f, sc);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(starts_with(s.error().message, path("c.bmp") + ": ")) << s.error().message;
  EXPECT_TRUE(entries().empty());
  ASSERT_TRUE(write_images({path("a.pfm"), path("b.exr"), path("c.png")}, f, sc).ok());
  EXPECT_EQ(entries().size(), 3u);
}

TEST_F(ImageIo, EmptyImageIsNotWritten) {
  const std::string p = path("empty.pfm");
  EXPECT_FALSE(io::write_pfm(p, ImageRgb()).ok());
  EXPECT_FALSE(io::write_exr(path("empty.exr"), ImageRgb()).ok());
  EXPECT_FALSE(io::write_png8(path("empty.png"), 0, 0, {}).ok());
  EXPECT_FALSE(io::write_png8(path("short.png"), 2, 2, {1, 2, 3}).ok());
  EXPECT_TRUE(entries().empty());
}

}  // namespace
}  // namespace penumbra::flatland
