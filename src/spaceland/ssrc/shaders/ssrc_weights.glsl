// ssrc.cpp's Gather::weights() one direction at a time: the weights of direction d's bins for a
// surface of normal n seen along v (nv = n . v), into w[0..bins).
void direction_weights(int d, vec3 v, vec3 n, float nv, out float w[8]) {
  precise vec3 sd = g.r.xyz * dirs[d].x - g.u.xyz * dirs[d].y;
  const float nt = dot3(n, slice_tangent(v, sd));
  const int above = above_of(slice_angle(-nt, nv), g.spr, g.sectors);
  for (int b = 0; b < g.bins; ++b) {
    w[b] = 0.0;
    if (b * g.per_bin >= above) continue;
    const int from = b * g.per_bin, to = min((b + 1) * g.per_bin, above);
    precise float wb =
        nv * (g.cos_sum[to] - g.cos_sum[from]) + nt * (g.sin_sum[to] - g.sin_sum[from]);
    w[b] = 0.0 < wb ? wb : 0.0;
  }
}
