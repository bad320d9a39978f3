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
  double largest = 0;  // the largest coordinate, which sets float rounding
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 c = corners[i];
    const double u = drop == 0 ? c.y : c.x, v = drop == 2 ? c.y : c.z;
    // (u, v) is right-handed about the dropped axis for x and z, left-handed for y.
    p[i] = {u, (drop == 1 ? -sign : sign) * v};
    largest = std::fmax(largest, std::fmax(std::fabs(u), std::fabs(v)));
  }
  // Corners of a fine circle wobble by their rounding: a few float ulps of the largest one, or
  // (OBJ files write 6 or 7 digits) a millionth of the face's size, whichever is more.
  double lo[2] = {p[0].x, p[0].y}, hi[2] = {p[0].x, p[0].y};
  for (const P2& q : p) {
    lo[0] = std::fmin(lo[0], q.x), lo[1] = std::fmin(lo[1], q.y);
    hi[0] = std::fmax(hi[0], q.x), hi[1] = std::fmax(hi[1], q.y);
  }
  const double noise =
      std::fmax(4 * 1.2e-7 * largest, 1e-6 * std::hypot(hi[0] - lo[0], hi[1] - lo[1]));
  auto area2 = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return turn(p[a], p[b], p[c]);
  };
  if (n == 4) {
    // Along the shorter diagonal, as tinyobjloader splits (meshes read before read the same),
    // unless that turns a triangle over (a concave quad): then the other.
    const Vec3 d02 = corners[2] - corners[0], d13 = corners[3] - corners[1];
    const bool first = dot(d02, d02) < dot(d13, d13);
    const bool first_ok = area2(0, 1, 2) >= 0 && area2(0, 2, 3) >= 0;
    const bool second_ok = area2(0, 1, 3) >= 0 && area2(1, 2, 3) >= 0;
    if (first ? first_ok || !second_ok : !(second_ok || !first_ok)) {
      out.push_back({0, 1, 2});
      out.push_back({0, 2, 3});
    } else {
      out.push_back({0, 1, 3});
      out.push_back({1, 2, 3});
    }
    return true;
  }
  // The ring of corners without repeats: a corner written twice in a row has no area and no
  // turn, and would hide a reflex corner from the ears.
  std::vector<std::uint32_t> ring;
  ring.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i)
    if (ring.empty() || !(corners[i] == corners[ring.back()])) ring.push_back(i);
  while (ring.size() > 1 && corners[ring.back()] == corners[ring.front()]) ring.pop_back();
  const std::size_t m = ring.size();
  auto fan = [&](const std::vector<std::uint32_t>& r) {
    for (std::size_t i = 1; i + 1 < r.size(); ++i) out.push_back({r[0], r[i], r[i + 1]});
  };
  if (m < 3) return true;  // no area at all
  // Convex: no corner turns back (beyond rounding), the turns add up to one revolution (a
  // pentagram turns the same way at every corner, twice around), and every fan triangle from
  // the first corner faces the same way (a fine concave arc turns back at each corner by less
  // than rounding, but the fan across it is turned over).
  bool convex = true;
  double turned = 0;
  for (std::size_t i = 0; i < m && convex; ++i) {
    const P2 a = p[ring[(i + m - 1) % m]], b = p[ring[i]], c = p[ring[(i + 1) % m]];
    const double sine = turn(a, b, c);
    convex = sine >= -noise * std::hypot(c.x - a.x, c.y - a.y);
    turned += std::atan2(sine, (b.x - a.x) * (c.x - b.x) + (b.y - a.y) * (c.y - b.y));
  }
  convex = convex && std::fabs(turned - 2 * std::numbers::pi) < 1e-3;
  for (std::size_t i = 1; i + 1 < m && convex; ++i) {
    const P2 a = p[ring[0]], b = p[ring[i]], c = p[ring[i + 1]];
    convex = turn(a, b, c) >=
             -noise * (std::hypot(b.x - a.x, b.y - a.y) + std::hypot(c.x - a.x, c.y - a.y));
  }
  work.steps += 2 * m;
  if (convex) {
    fan(ring);
    work.convex = true;
    return true;
  }
  // Ear clipping on the ring; only a corner that does not turn forward (reflex, or straight on)
  // can lie inside an ear.
  std::vector<std::uint32_t> prev(m), next(m);
  std::vector<char> reflex(m, 0), gone(m, 0);
  std::vector<std::uint32_t> reflexes;  // candidates, pruned lazily
  for (std::size_t i = 0; i < m; ++i) {
    prev[i] = std::uint32_t((i + m - 1) % m);
    next[i] = std::uint32_t((i + 1) % m);
  }
  auto at = [&](std::uint32_t i) { return p[ring[i]]; };
  auto update = [&](std::uint32_t i) {
    const bool was = reflex[i];
    reflex[i] = turn(at(prev[i]), at(i), at(next[i])) <= 0;
    if (reflex[i] && !was) reflexes.push_back(i);
  };
  for (std::uint32_t i = 0; i < m; ++i) update(i);
  const std::size_t start = out.size();
  std::size_t remaining = m, misses = 0;
  std::uint32_t cur = 0;
  while (remaining > 3) {
    const std::uint32_t a = prev[cur], c = next[cur];
    bool ear = !reflex[cur];
    if (ear) {
      std::size_t kept = 0;
      for (std::size_t k = 0; k < reflexes.size(); ++k) {
        const std::uint32_t r = reflexes[k];
        if (gone[r] || !reflex[r]) continue;  // clipped, or convex now
        reflexes[kept++] = r;
        if (r == a || r == c) continue;
        // A corner at the ear's own corners (the polygon touching itself) does not block it.
        const P2 q = at(r);
        if ((q.x == at(a).x && q.y == at(a).y) || (q.x == at(c).x && q.y == at(c).y)) continue;
        if (ear && inside(q, at(a), at(cur), at(c))) ear = false;
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
    out.push_back({ring[a], ring[cur], ring[c]});
    gone[cur] = 1;
    next[a] = c;
    prev[c] = a;
    --remaining;
    misses = 0;
    update(a);
    update(c);
    cur = c;
  }
  std::vector<std::uint32_t> rest;
  for (std::uint32_t i = cur, k = 0; k < remaining; ++k, i = next[i]) rest.push_back(ring[i]);
  fan(rest);
  return true;
}

}  // namespace penumbra::spaceland
