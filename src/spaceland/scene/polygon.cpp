#include "spaceland/scene/polygon.hpp"

#include <cmath>
#include <numbers>

namespace penumbra::spaceland {

namespace {

struct P2 {
  double x, y;
};

double turn(P2 a, P2 b, P2 c) {
  return (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
}

// Whether p lies in the counter-clockwise triangle abc (its edges included).
bool inside(P2 p, P2 a, P2 b, P2 c) {
  return turn(a, b, p) >= 0 && turn(b, c, p) >= 0 && turn(c, a, p) >= 0;
}

}  // namespace

bool triangulate_polygon(const std::vector<Vec3>& corners,
                         std::vector<std::array<std::uint32_t, 3>>& out, std::uint64_t max_steps,
                         PolygonWork& work) {
  work = {};
  const std::size_t n = corners.size();
  if (n < 3) return true;
  work.steps = n;
  if (n == 3) {
    out.push_back({0, 1, 2});
    return true;
  }
  if (n == 4) {
    const Vec3 d02 = corners[2] - corners[0], d13 = corners[3] - corners[1];
    if (dot(d02, d02) < dot(d13, d13)) {
      out.push_back({0, 1, 2});
      out.push_back({0, 2, 3});
    } else {
      out.push_back({0, 1, 3});
      out.push_back({1, 2, 3});
    }
    return true;
  }
  // The plane: Newell's normal; its largest axis is dropped, and the polygon made
  // counter-clockwise in the other two.
  double nx = 0, ny = 0, nz = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = corners[i], b = corners[(i + 1) % n];
    nx += (double(a.y) - b.y) * (double(a.z) + b.z);
    ny += (double(a.z) - b.z) * (double(a.x) + b.x);
    nz += (double(a.x) - b.x) * (double(a.y) + b.y);
  }
  const double ax = std::fabs(nx), ay = std::fabs(ny), az = std::fabs(nz);
  const int drop = ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
  const double sign = (drop == 0 ? nx : drop == 1 ? ny : nz) < 0 ? -1 : 1;
  std::vector<P2> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 c = corners[i];
    const double u = drop == 0 ? c.y : c.x, v = drop == 2 ? c.y : c.z;
    // (u, v) is right-handed about the dropped axis for x and z, left-handed for y.
    p[i] = {u, (drop == 1 ? -sign : sign) * v};
  }
  auto fan = [&](const std::vector<std::uint32_t>& ring) {
    for (std::size_t i = 1; i + 1 < ring.size(); ++i)
      out.push_back({ring[0], ring[i], ring[i + 1]});
  };
  // Convex: no turn the other way, and the turns add up to one revolution (a pentagram turns
  // the same way at every corner, twice around). Float corners of a fine circle wobble: a corner
  // that turns back by less than float rounding of the polygon's size (1e-6 of it from the line
  // through its neighbours) counts as straight on.
  double lo[2] = {p[0].x, p[0].y}, hi[2] = {p[0].x, p[0].y};
  for (const P2& q : p) {
    lo[0] = std::fmin(lo[0], q.x), lo[1] = std::fmin(lo[1], q.y);
    hi[0] = std::fmax(hi[0], q.x), hi[1] = std::fmax(hi[1], q.y);
  }
  const double noise = 1e-6 * std::hypot(hi[0] - lo[0], hi[1] - lo[1]);
  bool same_way = true;
  double turned = 0;
  for (std::size_t i = 0; i < n && same_way; ++i) {
    const P2 a = p[(i + n - 1) % n], b = p[i], c = p[(i + 1) % n];
    const double sine = turn(a, b, c);
    same_way = sine >= -noise * std::hypot(c.x - a.x, c.y - a.y);
    turned += std::atan2(sine, (b.x - a.x) * (c.x - b.x) + (b.y - a.y) * (c.y - b.y));
  }
  if (same_way && std::fabs(turned - 2 * std::numbers::pi) < 1e-3) {
    std::vector<std::uint32_t> ring(n);
    for (std::size_t i = 0; i < n; ++i) ring[i] = std::uint32_t(i);
    fan(ring);
    work.convex = true;
    return true;
  }
  // Ear clipping on a ring of corners; only a reflex corner can lie inside an ear.
  std::vector<std::uint32_t> prev(n), next(n);
  std::vector<char> reflex(n);
  std::vector<std::uint32_t> reflexes;  // candidates, pruned lazily
  for (std::size_t i = 0; i < n; ++i) {
    prev[i] = std::uint32_t((i + n - 1) % n);
    next[i] = std::uint32_t((i + 1) % n);
  }
  std::vector<char> gone(n, 0);
  auto update = [&](std::uint32_t i) {
    const bool was = reflex[i];
    reflex[i] = turn(p[prev[i]], p[i], p[next[i]]) < 0;
    if (reflex[i] && !was) reflexes.push_back(i);
  };
  for (std::uint32_t i = 0; i < n; ++i) update(i);
  const std::size_t start = out.size();
  std::size_t remaining = n, misses = 0;
  std::uint32_t cur = 0;
  while (remaining > 3) {
    const std::uint32_t a = prev[cur], c = next[cur];
    bool ear = !reflex[cur] && turn(p[a], p[cur], p[c]) > 0;
    if (ear) {
      std::size_t kept = 0;
      for (std::size_t k = 0; k < reflexes.size(); ++k) {
        const std::uint32_t r = reflexes[k];
        if (gone[r] || !reflex[r]) continue;  // clipped, or convex now
        reflexes[kept++] = r;
        if (r == a || r == c) continue;
        if (ear && inside(p[r], p[a], p[cur], p[c])) ear = false;
      }
      reflexes.resize(kept);
      work.steps += kept;
    }
    ++work.steps;
    if (work.steps > max_steps) {
      out.resize(start);
      return false;
    }
    if (!ear) {
      cur = c;
      if (++misses > remaining) break;  // no ear: the polygon crosses itself
      continue;
    }
    out.push_back({a, cur, c});
    gone[cur] = 1;
    next[a] = c;
    prev[c] = a;
    --remaining;
    misses = 0;
    update(a);
    update(c);
    cur = c;
  }
  std::vector<std::uint32_t> ring;
  for (std::uint32_t i = cur, k = 0; k < remaining; ++k, i = next[i]) ring.push_back(i);
  fan(ring);
  return true;
}

}  // namespace penumbra::spaceland
