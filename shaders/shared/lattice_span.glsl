// Scanline span of a tet on a lattice row, in float: the GPU twin of rowSpan()
// in geometry/raster/lattice_tets.cpp. Each face bounds the span at the root
// of its plane value along the row. The two tets of a shared face hold
// negated planes; with `precise` (no contraction) their plane values, and so
// their roots (a quotient of two negated numbers), are bitwise equal: one
// tet takes x >= root, the other x <= root, and the union of their spans has
// neither gap nor overlap except points exactly on the face, which both take.
// The CPU reference tests every point exactly instead; the two differ only
// for points within float rounding of a face.

bool rowSpan(RasterTet t, int y, int z, out int x0, out int x1) {
  float lo = float(t.loX);
  float hi = float(t.hiX);
  for (int k = 0; k < 4; ++k) {
    const RasterFace f = t.face[k];
    precise float rest = f.ny * float(y - f.ay) + f.nz * float(z - f.az) + f.d;
    const float root = float(f.ax) - rest / f.nx;
    if (f.nx > 0.0) lo = max(lo, ceil(root));
    if (f.nx < 0.0) hi = min(hi, floor(root));
    if (f.nx == 0.0 && rest < 0.0) hi = lo - 1.0;
  }
  x0 = int(t.loX);
  x1 = x0 - 1;
  if (!(lo <= hi)) return false;
  x0 = int(lo);
  x1 = int(hi);
  return true;
}
