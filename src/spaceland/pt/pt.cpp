#include "spaceland/pt/pt.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/sobol.hpp"
#include "core/timer.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/color.hpp"
#include "spaceland/lights.hpp"
#include "spaceland/media.hpp"
#include "spaceland/sampling.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::pt {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kInv4Pi = float(1 / (4 * kPi));

// Sobol pairs per scattering vertex: free flight, light pick, light point, sun, direction.
enum Pair : std::uint32_t { kFlight, kPick, kLightPoint, kSunPoint, kDirection, kPairs };

// Power heuristic (beta = 2) for a sample of density `a` against the other technique's `b`.
float mis(float a, float b) {
  // In double: the squares of the densities of a nearly degenerate emitter overflow a float.
  const double a2 = double(a) * a, b2 = double(b) * b;
  return a2 + b2 > 0 ? float(a2 / (a2 + b2)) : 0.0f;
}

struct Context {
  const Scene& scene;
  const RayScene& rays;
  const Lights& lights;
  const Media& media;
  int bounces;
};

// A scattering vertex: a surface point (normals faced towards the arriving ray) or a point in
// fog.
struct Vertex {
  Vec3 p;
  bool in_medium = false;
  Vec3 ng, ns, wo;  // surface only; wo: towards where the light goes on
  Brdf brdf;
};

// Density of the direction sampler at a vertex for direction wi (a mirror's delta excluded).
float direction_pdf(const Vertex& v, Vec3 wi) {
  if (v.in_medium) return kInv4Pi;
  return brdf_pdf(v.brdf, v.ns, v.ng, v.wo, wi);
}

// BSDF (or phase function) times the cosine, for light arriving along wi; none from below the
// surface.
Rgb scattering(const Vertex& v, Vec3 wi) {
  if (v.in_medium) return Rgb{kInv4Pi, kInv4Pi, kInv4Pi};
  return brdf_cos(v.brdf, v.ns, v.ng, v.wo, wi);
}

// A shadow ray from the vertex to a sampled emitter point, or to the sky for the sun; both ends
// are kept off their surfaces.
Ray shadow(const Context& ctx, const Vertex& v, const LightSample& ls) {
  const Vec3 wi = ls.direction;
  const float distance = ls.distance;
  if (!v.in_medium) {
    if (distance == kInf) return Ray{ctx.rays.spawn(v.p, v.ng, wi), wi, 0, kInf};
    return ctx.rays.shadow_ray(v.p, v.ng, ls.point, ls.normal);
  }
  // In fog there is no surface to leave: the point is moved (by the same tiny offset) towards the
  // light, and the far end is kept off the light's surface as from a surface point.
  if (distance == kInf) return Ray{v.p, wi, 0, kInf};
  return ctx.rays.shadow_ray(v.p, wi, ls.point, ls.normal);
}

// Light from one sampled emitter point (or the sun) through the vertex, MIS-weighted against
// the direction sampler.
Rgb direct(const Context& ctx, const Vertex& v, const LightSample& ls, std::uint64_t& rays) {
  if (!(ls.pdf > 0) || is_black(ls.radiance)) return {};
  const Rgb f = scattering(v, ls.direction);
  if (is_black(f)) return {};
  const Ray r = shadow(ctx, v, ls);
  ++rays;
  if (ls.sun) {
    if (ctx.rays.occluded(r)) return {};
  } else {
    // Closest hit, not any hit: meeting the sampled emitter itself (a grazing ray on a sphere's
    // rim meets it a hair before the sampled point) is reaching it.
    Hit h;
    if (ctx.rays.intersect(r, h) && !ls.is(h)) return {};
  }
  Rgb tr{1, 1, 1};
  if (!ctx.media.empty()) {
    tr = ctx.media.transmittance(Ray{v.p, ls.direction, 0, kInf}, ls.distance);
  }
  const float w = mis(ls.pdf, direction_pdf(v, ls.direction));
  return f * ls.radiance * tr * (w / ls.pdf);
}

// One sample of the radiance arriving at `origin` along -dir, from the ray's first stretch
// [0, t_end] (its first hit `hit` where `found`, within it) and the paths that scatter there: the
// camera's ray through a pixel (t_end infinite), or one interval of a radiance field, where a
// stretch that ends in empty space adds no sky (the next interval holds what lies past it).
Rgb trace(const Context& ctx, Vec3 origin, Vec3 dir, Hit hit, bool found, float t_end,
          std::uint32_t pixel_seed, std::uint32_t sample, std::vector<MediumPiece>& pieces,
          std::uint64_t& rays) {
  auto point = [&](int vertex, Pair pair) {
    return sobol::sample_2d(sample, pixel_seed, std::uint32_t(vertex) * kPairs + pair);
  };
  Rgb L{}, beta{1, 1, 1};
  float prev_pdf = 0;  // density the direction sampler gave to `dir` (0 from the camera)
  Vec3 prev_p = origin;
  for (int scatters = 0;; ++scatters) {
    Vertex v;
    bool scattered_in_fog = false;
    if (!ctx.media.empty()) {
      const float t_stop = found ? hit.t : t_end;
      ctx.media.pieces(Ray{origin, dir, 0, t_stop}, t_stop, pieces);
      if (!pieces.empty()) {
        L += beta * Media::emitted(pieces);
        if (scatters < ctx.bounces) {
          const std::array<float, 2> u = point(scatters, kFlight);
          const FreeFlight ff = Media::sample(pieces, u[0], u[1]);
          beta *= ff.weight;
          if (ff.scattered) {
            scattered_in_fog = true;
            v.in_medium = true;
            v.p = origin + dir * ff.t;
          }
        } else {
          beta *= ctx.media.transmittance(Ray{origin, dir, 0, kInf}, t_stop);
        }
      }
    }
    if (!scattered_in_fog) {
      if (!found && t_end < kInf) break;  // the stretch ends before anything: no sky from it
      if (!found) {
        const Background& bg = ctx.lights.background();
        L += beta * bg.sky(dir);
        if (bg.in_sun(dir)) {
          const float w = prev_pdf > 0 ? mis(prev_pdf, ctx.lights.sun_pdf()) : 1.0f;
          L += beta * bg.sun() * w;
        }
        break;
      }
      const Rgb le = emission_at(ctx.scene, hit);
      if (!is_black(le)) {
        const float w = prev_pdf > 0 ? mis(prev_pdf, ctx.lights.pdf(prev_p, hit)) : 1.0f;
        L += beta * le * w;
      }
      if (scatters == ctx.bounces) break;
      v.p = hit.position;
      v.ng = hit.geometric_normal;
      v.ns = hit.shading_normal;
      v.wo = -dir;
      v.brdf = brdf_at(ctx.scene, hit);
      // A black Lambertian reflects nothing; a glossy surface always reflects (Fresnel).
      if (v.brdf.lambertian && is_black(v.brdf.diffuse)) break;
    }
    // Next event estimation: one emitter point and the sun.
    if (!ctx.lights.empty()) {
      const LightSample ls =
          ctx.lights.sample(v.p, point(scatters, kPick)[0], point(scatters, kLightPoint));
      L += beta * direct(ctx, v, ls, rays);
    }
    if (ctx.lights.has_sun()) {
      const LightSample ls = ctx.lights.sample_sun(point(scatters, kSunPoint));
      L += beta * direct(ctx, v, ls, rays);
    }
    // The next direction: from the BRDF (cosine-weighted for the Lambertian: albedo / pi x cos /
    // pdf = albedo), or isotropic in fog (its albedo is already in the free-flight weight). The
    // lobe is picked with the light pick's unused second number, so that Lambertian scenes draw
    // the very numbers they drew before glossy materials.
    const std::array<float, 2> u = point(scatters, kDirection);
    Vec3 wi;
    if (v.in_medium) {
      wi = uniform_sphere(u);
      prev_pdf = kInv4Pi;
      origin = v.p;
    } else {
      const BrdfSample bs = sample_brdf(v.brdf, v.ns, v.ng, v.wo, point(scatters, kPick)[1], u);
      if (is_black(bs.weight)) break;  // under the surface: this path carries nothing
      wi = bs.wi;
      prev_pdf = bs.pdf;  // 0 after a mirror: what it meets counts in full (no light sample)
      beta *= bs.weight;
      origin = ctx.rays.spawn(v.p, v.ng, wi);
    }
    prev_p = v.p;
    dir = wi;
    ++rays;
    found = ctx.rays.intersect(Ray{origin, dir, 0, kInf}, hit);
    if (found) face_towards(hit, dir);
    t_end = kInf;  // past the first vertex, every ray runs to its hit or the sky
    if (is_black(beta)) break;
  }
  return L;
}

}  // namespace

SegmentTracer::SegmentTracer(const Scene& scene, const RayScene& rays, int bounces)
    : scene_(scene), rays_(rays), lights_(scene), media_(scene), bounces_(bounces) {}

Segment SegmentTracer::trace(Vec3 origin, Vec3 dir, float t_end, float lead, std::uint32_t seed,
                             std::uint32_t sample, std::vector<MediumPiece>& pieces,
                             std::uint64_t& rays) const {
  const Context ctx{scene_, rays_, lights_, media_, bounces_};
  Segment s;
  Hit hit;
  if (lead > 0) {
    // A surface in the lead-in is the stretch's, opaque: the light leaving it towards the origin,
    // with no fog before it (the stretches below hold that).
    const Vec3 back = origin - dir * lead;
    ++rays;
    if (rays_.intersect(Ray{back, dir, 0, lead}, hit)) {
      face_towards(hit, dir);
      const Vec3 at = back + dir * hit.t;
      hit.t = 0;
      s.radiance = pt::trace(ctx, at, dir, hit, true, t_end, seed, sample, pieces, rays);
      return s;
    }
  }
  ++rays;
  const bool found = rays_.intersect(Ray{origin, dir, 0, t_end}, hit);
  if (found) face_towards(hit, dir);
  s.radiance = pt::trace(ctx, origin, dir, hit, found, t_end, seed, sample, pieces, rays);
  if (!found) {
    s.transmittance =
        media_.empty() ? Rgb{1, 1, 1} : media_.transmittance(Ray{origin, dir, 0, kInf}, t_end);
  }
  return s;
}

ImageRgb render(const SolveContext& in, const PtOptions& pt, SolveReport& report) {
  Stopwatch stage;
  const Scene& scene = in.scene;
  const GBuffer& g = in.g;
  const Lights lights(scene);
  const Media media(scene);
  const Context ctx{scene, in.rays, lights, media, in.bounces};
  const Vec3 camera = scene.camera.position;
  const int w = g.width, h = g.height;
  const std::size_t n = std::size_t(w) * h;
  std::vector<double> sum(n * 3, 0.0);
  std::atomic<std::uint64_t> ray_count{0};
  const std::uint32_t seed = sobol::hash(pt.seed);

  const std::uint64_t target = pt.spp > 0 ? std::uint64_t(pt.spp) : 0;
  Stopwatch watch;
  std::uint64_t done = 0;
  // Passes double in size (1, 2, 4, ... up to 64 samples), so that a time limit or Ctrl-C is
  // honoured soon; a pixel's samples are summed in index order, so passes change no bit. With a
  // time limit a pass holds no more samples than the time left allows at the rate so far, so
  // that the last one does not run on past it (a 64-sample pass can take a second).
  while (true) {
    if (target > 0 && done >= target) break;
    std::uint64_t pass = std::min<std::uint64_t>(std::max<std::uint64_t>(done, 1), 64);
    if (target > 0) pass = std::min(pass, target - done);
    if (pt.seconds > 0 && done > 0) {
      const double elapsed = watch.ms() / 1000, per_sample = elapsed / double(done);
      const double fit = std::floor((pt.seconds - elapsed) / std::max(per_sample, 1e-12));
      pass = std::min(pass, std::uint64_t(std::max(1.0, std::min(fit, 64.0))));
    }
    const std::uint32_t s0 = std::uint32_t(done), s1 = std::uint32_t(done + pass);
    parallel_for(h, [&](int j) {
      std::vector<MediumPiece> pieces;
      std::uint64_t local_rays = 0;
      for (int i = 0; i < w; ++i) {
        const std::size_t k = std::size_t(j) * w + i;
        const std::uint32_t pixel_seed = sobol::hash((std::uint64_t(seed) << 32) | k);
        double acc[3] = {sum[3 * k], sum[3 * k + 1], sum[3 * k + 2]};
        for (std::uint32_t s = s0; s < s1; ++s) {
          const Rgb c = trace(ctx, camera, g.directions[k], g.hits[k], g.found[k] != 0, kInf,
                              pixel_seed, s, pieces, local_rays);
          // A sample that is not finite would poison the pixel; none is expected (every
          // division is guarded), and tests check that images stay finite.
          if (!std::isfinite(c.r) || !std::isfinite(c.g) || !std::isfinite(c.b)) continue;
          acc[0] += c.r;
          acc[1] += c.g;
          acc[2] += c.b;
        }
        sum[3 * k] = acc[0];
        sum[3 * k + 1] = acc[1];
        sum[3 * k + 2] = acc[2];
      }
      ray_count.fetch_add(local_rays, std::memory_order_relaxed);
    });
    done += pass;
    const double elapsed = watch.ms() / 1000;
    const bool cancelled = in.cancel && in.cancel->load();
    const bool timed_out = pt.seconds > 0 && elapsed >= pt.seconds;
    if (in.progress && *in.progress) {
      RenderProgress p;
      p.samples = done;
      p.target = target;
      p.elapsed_s = elapsed;
      const double by_samples = target > 0 ? double(done) / double(target) : 0;
      const double by_time = pt.seconds > 0 ? elapsed / pt.seconds : 0;
      p.fraction = std::min(1.0, std::max(by_samples, by_time));
      (*in.progress)(p);
    }
    if (cancelled) {
      report.cancelled = target == 0 || done < target;
      break;
    }
    if (timed_out) break;
  }
  report.samples = done;
  report.rays += ray_count.load();
  ImageRgb img(w, h);
  const double inv = done > 0 ? 1.0 / double(done) : 0;
  for (std::size_t k = 0; k < n * 3; ++k) img.data()[k] = float(sum[k] * inv);
  report.stages.push_back({"path trace", stage.ms()});
  report.memory_bytes += working_bytes(w, h);
  return img;
}

}  // namespace penumbra::spaceland::pt
