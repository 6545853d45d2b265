// Scanline span of a tet on a lattice row: GLSL twin of rowSpan() in
// geometry/deform/lattice_tets.cpp, in float. Plane values are `precise` (no
// contraction) so the two tets of a shared face compute exact negatives and
// the union of their closed sets has no cracks.

bool facePasses(RasterFace f, float rest, int x) {
  precise float v = f.nx * float(x - f.ax) + rest;
  return v >= 0.0;
}

// Lattice points x0..x1 of row (y, z) inside tet t; false when none.
bool rowSpan(RasterTet t, int y, int z, out int x0, out int x1) {
  int lo = t.loX;
  int hi = t.hiX;
  x0 = lo;
  x1 = hi;
  for (int k = 0; k < 4 && lo <= hi; ++k) {
    const RasterFace f = t.face[k];
    precise float rest = f.ny * float(y - f.ay) + f.nz * float(z - f.az) + f.d;
    if (f.nx > 0.0) {
      // From the real root, step to the exact first passing point: the
      // evaluation is monotone in x.
      const float root = float(f.ax) - rest / f.nx;
      int c = root > float(lo) ? (root < float(hi) + 1.0 ? int(ceil(root)) : hi + 1) : lo;
      while (c > lo && facePasses(f, rest, c - 1)) --c;
      while (c <= hi && !facePasses(f, rest, c)) ++c;
      lo = c;
    } else if (f.nx < 0.0) {
      const float root = float(f.ax) - rest / f.nx;
      int c = root < float(hi) ? (root > float(lo) - 1.0 ? int(floor(root)) : lo - 1) : hi;
      while (c < hi && facePasses(f, rest, c + 1)) ++c;
      while (c >= lo && !facePasses(f, rest, c)) --c;
      hi = c;
    } else if (!facePasses(f, rest, lo)) {
      return false;
    }
  }
  x0 = lo;
  x1 = hi;
  return lo <= hi;
}
