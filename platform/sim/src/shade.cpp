// Procedural materials: asphalt with markings, paving, kerbs, facades (brick, plaster, panels; windows,
// doors, shops), foliage, bark, signs, car paint and glass, tyres, clothes, grass, walls, sky.
#include "shade.hpp"

#include <algorithm>
#include <cmath>

namespace beslam::sim::detail {
namespace {

constexpr int kTile = 256;

inline float ffloor(float x) {
  const float t = static_cast<float>(static_cast<int>(x));
  return t - (x < t ? 1.f : 0.f);
}
inline float fract(float x) { return x - ffloor(x); }

// Value noise at tile pixel (x, y) with `period` lattice cells across the tile: the lattice values
// L(a, b) (L wraps a and b itself) interpolated with a smoothstep between the four corners.
template <class Lattice>
float latticeNoise(int x, int y, int period, const Lattice& L) {
  const float cell = static_cast<float>(kTile) / period;
  const float fx = x / cell, fy = y / cell;
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  float tx = fx - x0, ty = fy - y0;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const float top = L(x0, y0) + tx * (L(x0 + 1, y0) - L(x0, y0));
  const float bot = L(x0, y0 + 1) + tx * (L(x0 + 1, y0 + 1) - L(x0, y0 + 1));
  return top + ty * (bot - top);
}

struct Tile {
  float v[kTile * kTile];
  Tile() {
    // Sum of tileable value-noise octaves with periods 4..128 lattice cells per tile.
    std::vector<float> acc(kTile * kTile, 0.f);
    float total = 0, amp = 1.0f;
    for (int period = 4; period <= 128; period *= 2) {
      std::vector<float> lattice(static_cast<std::size_t>(period) * period);
      for (int i = 0; i < period * period; ++i)
        lattice[i] = hashf(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(period), 12345u);
      auto L = [&](int a, int b) { return lattice[(b % period) * period + (a % period)]; };
      for (int y = 0; y < kTile; ++y)
        for (int x = 0; x < kTile; ++x) acc[y * kTile + x] += amp * latticeNoise(x, y, period, L);
      total += amp;
      amp *= 0.62f;
    }
    // Normalise to [0, 1] with a stretched contrast.
    float lo = 1e9f, hi = -1e9f;
    for (float a : acc) lo = std::min(lo, a), hi = std::max(hi, a);
    for (int i = 0; i < kTile * kTile; ++i) v[i] = (acc[i] - lo) / (hi - lo);
    (void)total;
  }
};

const Tile& tile() {
  static const Tile t;
  return t;
}

// Single-octave value noise, 64 x 64 cells over the 256 x 256 tile (smoothstep-interpolated).
struct CellTile {
  float v[kTile * kTile];
  CellTile() {
    const int period = 64;
    auto L = [&](int a, int b) {
      return hashf(static_cast<std::uint32_t>(a % period), static_cast<std::uint32_t>(b % period), 999u);
    };
    for (int y = 0; y < kTile; ++y)
      for (int x = 0; x < kTile; ++x) v[y * kTile + x] = latticeNoise(x, y, period, L);
  }
};

const CellTile& cellTile() {
  static const CellTile t;
  return t;
}

// Bilinear lookup in a kTile x kTile periodic table at (x, y) table cells.
inline float wrappedBilinear(const float* table, float x, float y) {
  int ix = static_cast<int>(x), iy = static_cast<int>(y);
  ix -= x < static_cast<float>(ix);
  iy -= y < static_cast<float>(iy);
  const float tx = x - static_cast<float>(ix), ty = y - static_cast<float>(iy);
  const int xi = ix & (kTile - 1), yi = iy & (kTile - 1);
  const int x1 = (xi + 1) & (kTile - 1), y1 = (yi + 1) & (kTile - 1);
  const float a = table[yi * kTile + xi], b = table[yi * kTile + x1], c = table[y1 * kTile + xi],
              d = table[y1 * kTile + x1];
  const float top = a + tx * (b - a), bot = c + tx * (d - c);
  return top + ty * (bot - top);
}

// Multi-octave tileable noise (the Tile above), bilinear between its cells.
inline float N(float u, float v) { return wrappedBilinear(tile().v, u * kTile, v * kTile); }

// Value noise with unit cells (period 64 cells), in [0, 1].
inline float V(float u, float v) { return wrappedBilinear(cellTile().v, u * 4.f, v * 4.f); }

// Band-limited multi-octave detail in [-0.5, 0.5] per octave: cells of `cell`, 3 cell, 9 cell ...;
// an octave fades in once its cells span more than about 2.5 pixels (so nothing aliases).
inline float detail(float u, float v, float cell, int octaves, float fp, float seed) {
  float sum = 0;
  for (int k = 0; k < octaves; ++k, cell *= 3.f) {
    const float w = std::clamp(cell / (1.6f * fp) - 1.f, 0.f, 1.f);
    if (w <= 0.f) continue;
    sum += w * (V(u / cell + seed + 17.3f * k, v / cell - seed * 0.7f + 5.1f * k) - 0.5f);
  }
  return sum;
}

// Sharp-edged random flecks (stones, leaves, grit): one per cell at a random place, size and shade,
// round or square; in [-1, 1] where a fleck is, 0 elsewhere; fades out once a cell is under ~2 pixels.
inline float speckle(float u, float v, float cell, float fp, std::uint32_t seed) {
  const float w = std::clamp(cell / (2.5f * fp) - 1.f, 0.f, 1.f);  // flecks are about half a cell wide
  if (w <= 0.f) return 0.f;
  const float x = u / cell, y = v / cell;
  const float fx = ffloor(x), fy = ffloor(y);
  const std::uint32_t h =
      hash3(static_cast<std::uint32_t>(static_cast<int>(fx)), static_cast<std::uint32_t>(static_cast<int>(fy)), seed);
  const float px = 0.45f + 0.1f * static_cast<float>(h & 255) / 255.f,
              py = 0.45f + 0.1f * static_cast<float>((h >> 8) & 255) / 255.f;
  const float r = 0.2f + 0.22f * static_cast<float>((h >> 16) & 127) / 127.f;
  const float val = static_cast<float>(h >> 24) / 127.5f - 1.f;
  const float dx = std::abs(x - fx - px), dy = std::abs(y - fy - py);
  const float d = (h & 0x800000u) ? std::max(dx, dy) : std::sqrt(dx * dx + dy * dy);
  const float cov = std::clamp((r - d) * cell / fp + 0.5f, 0.f, 1.f);
  return val * cov * w;
}

// Anti-aliased coverage of a line of width w at distance d (box filter of one pixel footprint).
inline float lineCov(float d, float w, float fp) {
  return std::clamp((0.5f * (w + fp) - std::abs(d)) / fp, 0.f, std::min(1.f, w / fp));
}

// Weight of a detail of size `feature` metres seen with `fp` metres per pixel.
inline float fade(float feature, float fp) { return std::clamp(feature / fp - 1.0f, 0.0f, 1.0f); }

inline Vec3f grey(float g) { return Vec3f(g, g, g); }
inline Vec3f mix(const Vec3f& a, const Vec3f& b, float t) { return a + (b - a) * t; }
inline float box(float x, float lo, float hi) { return (x >= lo && x <= hi) ? 1.f : 0.f; }

Vec3f road(const World& w, const Street& st, float u, float v, float fp) {
  const float sf = static_cast<float>(st.seed % 997) * 0.37f;
  const float patches = N(u / 40.f + 0.3f, v / 40.f + static_cast<float>(st.seed % 97) * 0.01f);
  float c = 0.30f + 0.16f * detail(u, v, 0.012f, 4, fp, sf) + 0.12f * (patches - 0.5f) +
            0.24f * speckle(u, v, 0.03f, fp, st.seed) + 0.2f * speckle(u + 0.5f, v, 0.09f, fp, st.seed + 1);
  // Tyre wear along the lanes and the odd dark stain.
  const float stain = N(u / 9.f + sf, v / 9.f);
  if (stain > 0.68f) c *= 1.f - 1.2f * (stain - 0.68f);
  // Tar seams and repairs.
  if (fract(u / 23.7f) < 0.02f && fade(0.15f, fp) > 0) c *= 0.75f;
  const float a = std::abs(v);
  const float lw = st.lane_w;
  const float drive = st.lanes * lw;
  float mark = 0;
  if (st.median) {
    if (a > 0.15f && a < 0.30f) mark = 1;
    if (std::abs(a - drive) < 0.10f) mark = 1;
    for (int k = 1; k < st.lanes; ++k)
      if (std::abs(a - k * lw) < 0.08f && fract((u + (v > 0 ? 0.f : 4.f)) / 18.f) < 0.33f) mark = 1;
  } else {
    if (st.lanes == 1) {
      if (a < 0.06f && fract(u / 9.f) < 0.33f) mark = 1;
    } else if (a > 0.06f && a < 0.18f) {
      mark = 1;
    }
    for (int k = 1; k < st.lanes; ++k)
      if (std::abs(a - k * lw) < 0.06f && fract(u / 9.f) < 0.33f) mark = 1;
    if (st.parking_w > 0) {
      if (std::abs(a - drive) < 0.06f) mark = 1;
      if (a > drive && a < drive + st.parking_w && fract((u + 1.3f) / 5.6f) < 0.02f) mark = 1;
    }
    // Crosswalks and stop lines at both ends.
    const float across = drive + st.parking_w;
    if (a < across - 0.2f) {
      const bool nearStart = st.crosswalk_start && u > 0.8f && u < 4.6f;
      const bool nearEnd = st.crosswalk_end && u > st.length - 4.6f && u < st.length - 0.8f;
      if ((nearStart || nearEnd) && fract((v + 20.f) / 1.0f) < 0.5f) mark = 1;
      if (a < drive && ((v > 0 && u > 5.2f && u < 5.6f) || (v < 0 && u > st.length - 5.6f && u < st.length - 5.2f)))
        mark = 1;
    }
    // Manholes in some lanes.
    const float cell = ffloor(u / 17.f);
    const float hsh = hashf(st.seed, static_cast<std::uint32_t>(static_cast<int>(cell) + 1000), 3);
    if (hsh < 0.45f) {
      const float cu =
          cell * 17.f + 3.f + 11.f * hashf(st.seed, static_cast<std::uint32_t>(static_cast<int>(cell) + 1000), 4);
      const float cv = (hsh < 0.22f ? 1.f : -1.f) *
                       (0.5f + (lw - 1.0f) * hashf(st.seed, static_cast<std::uint32_t>(static_cast<int>(cell)), 5));
      const float r = std::hypot(u - cu, v - cv);
      if (r < 0.32f) {
        c = 0.22f + (r > 0.27f ? 0.12f : 0.f) +
            ((fract((u - cu) / 0.08f) < 0.5f) != (fract((v - cv) / 0.08f) < 0.5f) ? 0.07f : 0.f) * fade(0.08f, fp);
      }
    }
  }
  (void)w;
  if (mark > 0) {
    const float wear = 0.75f + 0.3f * N(u / 3.f, v / 3.f);
    c = c + (0.86f * wear - c) * mark;
  }
  return grey(c) + Vec3f(0.0f, 0.003f, 0.01f);
}

Vec3f asphalt(float u, float v, float fp) {
  return grey(0.30f + 0.16f * detail(u, v, 0.012f, 4, fp, 3.3f) + 0.10f * (N(u / 50.f, v / 50.f) - 0.5f) +
              0.24f * speckle(u, v, 0.03f, fp, 5) + 0.2f * speckle(u, v, 0.09f, fp, 6));
}

Vec3f pavement(float u, float v, float fp) {
  const float s = 0.5f;
  const float row = ffloor(v / s);
  const float uu = u + (static_cast<int>(row) & 1) * 0.25f;
  const float col = ffloor(uu / s);
  const float h =
      hashf(static_cast<std::uint32_t>(static_cast<int>(col)), static_cast<std::uint32_t>(static_cast<int>(row)), 11);
  const float tint = fade(s * 0.5f, fp);
  float c = 0.55f + 0.45f * (h - 0.5f) * tint + 0.14f * detail(u, v, 0.01f, 3, fp, 1.7f) +
            0.2f * speckle(u, v, 0.025f, fp, 7) + 0.15f * speckle(u, v, 0.08f, fp, 8);
  const float fu = fract(uu / s), fv = fract(v / s);
  const float joint =
      std::max(lineCov(std::min(fu, 1.f - fu) * s, 0.012f, fp), lineCov(std::min(fv, 1.f - fv) * s, 0.012f, fp));
  c -= 0.3f * joint;
  c += 0.10f * (N(u / 30.f, v / 30.f) - 0.5f);
  return Vec3f(c * 1.02f, c, c * 0.96f);
}

Vec3f kerb(float u, float v, float fp) {
  float c = 0.62f + 0.24f * detail(u, v, 0.01f, 3, fp, 9.1f);
  const float fu = fract(u);
  c -= 0.3f * lineCov(std::min(fu, 1.f - fu), 0.012f, fp);
  return grey(c);
}

// The wall material of a facade, evaluated only where no opening or trim covers it.
Vec3f facadeWall(const Facade& f, float u, float v, float fp) {
  const std::uint32_t sd = f.seed;
  if (v < 0.45f) return f.trim_colour * (0.85f + 0.3f * N(u / 2.f, v / 2.f) + 0.4f * detail(u, v, 0.01f, 3, fp, 3.f));
  const float stain = N(u / 25.f + static_cast<float>(sd % 113) * 0.01f, v / 25.f);
  Vec3f c = f.colour * (0.85f + 0.3f * (stain - 0.5f) + 0.3f * speckle(u, v, 0.07f, fp, sd + 3) +
                        0.25f * speckle(u, v, 0.2f, fp, sd + 4) + 0.2f * speckle(u, v, 0.55f, fp, sd + 5));
  if (f.base == 0) {  // brick
    const float row = ffloor(v / f.brick_h);
    const float off = (static_cast<int>(row) & 1) * f.brick_w * 0.5f;
    const float col = ffloor((u + off) / f.brick_w);
    const float fu = fract((u + off) / f.brick_w), fv = fract(v / f.brick_h);
    const float tint = 0.62f + 0.75f * hashf(sd, static_cast<std::uint32_t>(static_cast<int>(row)),
                                             static_cast<std::uint32_t>(static_cast<int>(col)));
    const float bw = fade(f.brick_h * 0.8f, fp);
    const Vec3f brick = c * (1.0f + (tint - 0.97f) * bw) * (1.f + 0.25f * detail(u, v, 0.008f, 2, fp, 2.f));
    const float mortar = std::max(lineCov(std::min(fu, 1.f - fu) * f.brick_w, 0.01f, fp),
                                  lineCov(std::min(fv, 1.f - fv) * f.brick_h, 0.01f, fp));
    return mix(brick, Vec3f(0.72f, 0.70f, 0.66f), mortar);
  }
  if (f.base == 1)  // plaster
    return c * (1.0f + 0.45f * detail(u, v, 0.015f, 4, fp, static_cast<float>(sd % 101)) +
                0.25f * speckle(u, v, 0.08f, fp, sd));
  // concrete panels
  const float pc = ffloor(u / f.panel_w), pr = ffloor(v / f.floor_h);
  c = c *
      (0.85f + 0.3f * hashf(sd, static_cast<std::uint32_t>(static_cast<int>(pc)),
                            static_cast<std::uint32_t>(static_cast<int>(pr)))) *
      (1.0f + 0.35f * detail(u, v, 0.015f, 4, fp, static_cast<float>(sd % 89)));
  const float pu = fract(u / f.panel_w), pv = fract(v / f.floor_h);
  return c * (1.0f - 0.5f * std::max(lineCov(std::min(pu, 1.f - pu) * f.panel_w, 0.03f, fp),
                                     lineCov(std::min(pv, 1.f - pv) * f.floor_h, 0.03f, fp)));
}

// Posters, stickers and patches of repair near street level, then quoins (alternating corner stones)
// and the top trim: true with `out` set where one of them covers (u, v).
bool facadeTrim(const Facade& f, float u, float v, float fp, float style, Vec3f& out) {
  const std::uint32_t sd = f.seed;
  // Posters, stickers and patches of repair near street level.
  if (v > 0.5f && v < 2.6f) {
    const float cu = ffloor(u / 1.7f), cv = ffloor(v / 1.05f);
    const std::uint32_t hp = hash3(sd, static_cast<std::uint32_t>(static_cast<int>(cu)),
                                   static_cast<std::uint32_t>(static_cast<int>(cv)) + 77u);
    if ((hp & 255) < 70) {
      const float pu = u / 1.7f - cu, pv = v / 1.05f - cv;
      const float w0 = 0.15f + 0.2f * static_cast<float>((hp >> 8) & 15) / 15.f,
                  h0 = 0.12f + 0.25f * static_cast<float>((hp >> 12) & 15) / 15.f;
      if (pu > w0 && pu < 1.f - w0 * 0.5f && pv > h0 && pv < 1.f - h0 * 0.5f) {
        const Vec3f pc(hashf(hp, 1, 2), hashf(hp, 2, 3), hashf(hp, 3, 4));
        out = mix(pc, grey(0.9f), 0.3f) * (0.8f + 0.4f * (fract(pv * 9.f) < 0.5f ? 1.f : 0.f) * fade(0.06f, fp));
        return true;
      }
    }
  }
  // Quoins: alternating corner stones.
  if (style < 0.5f && v > 0.45f && (u < 0.5f || u > f.length - 0.5f)) {
    const float row = ffloor(v / 0.32f);
    const float width = (static_cast<int>(row) & 1) ? 0.32f : 0.5f;
    const float e = u < 0.5f ? u : f.length - u;
    if (e < width) {
      const float fv = fract(v / 0.32f);
      Vec3f q =
          f.trim_colour * 1.35f * (0.9f + 0.2f * hashf(sd, static_cast<std::uint32_t>(static_cast<int>(row)), 43));
      q *= 1.f - 0.4f * std::max(lineCov(std::min(fv, 1.f - fv) * 0.32f, 0.012f, fp), lineCov(width - e, 0.012f, fp));
      out = q;
      return true;
    }
  }
  if (v > f.height - 0.45f) {
    out = f.trim_colour * (0.9f + 0.2f * N(u / 3.f, 0.3f));
    return true;
  }
  return false;
}

// Glass of an opening (window, door pane or shop bay) at (lu, lv) inside its ww x wh pane: reflections,
// curtains, blinds or light, and the glazing bars; key picks the opening's own look.
Vec3f facadeGlass(const Facade& f, float u, float v, float fp, float style, float lu, float lv, float ww, float wh,
                  std::uint32_t key) {
  const std::uint32_t sd = f.seed;
  const float h = hashf(sd, key, 21);
  const float refl = 0.10f + 0.16f * (lv / wh) + 0.10f * N(u / 6.f + h, v / 6.f);
  Vec3f g(refl * 0.9f, refl, refl * 1.12f);
  if (h < 0.33f) {  // curtains from the sides
    const float open = 0.15f + 0.3f * hashf(sd, key, 22);
    if (lu < ww * open || lu > ww * (1 - open))
      g = Vec3f(0.75f, 0.72f, 0.65f) * (0.8f + 0.3f * hashf(sd, key, 23)) *
          (0.9f + 0.1f * std::sin(lu * 40.f) * fade(0.04f, fp));
  } else if (h < 0.5f) {  // blinds
    const float down = wh * (0.2f + 0.7f * hashf(sd, key, 24));
    if (lv > wh - down) g = grey(0.6f + 0.15f * (fract(lv / 0.05f) < 0.5f ? 1.f : 0.f) * fade(0.025f, fp));
  } else if (h > 0.93f) {  // lit
    g = Vec3f(0.85f, 0.78f, 0.55f);
  }
  const float cols = ww > 1.2f ? 2.f : 1.f;
  const float rows = (style > 0.45f) ? 3.f : (h > 0.6f ? 2.f : 1.f);
  const float pu = fract(lu / ww * cols), pv = fract(lv / wh * rows);
  const float bar = std::max(lineCov(std::min(pu, 1.f - pu) * ww / cols, 0.05f, fp),
                             lineCov(std::min(pv, 1.f - pv) * wh / rows, 0.04f, fp));
  return mix(g, f.frame_colour, bar);
}

// The ground floor's door and shop front (sign band with lettering, bays of glass): true with `out` set
// where one of them covers (u, v).
bool facadeShopFront(const Facade& f, float u, float v, float fp, float style, Vec3f& out) {
  const std::uint32_t sd = f.seed;
  auto glass = [&](float lu, float lv, float ww, float wh, std::uint32_t key) {
    return facadeGlass(f, u, v, fp, style, lu, lv, ww, wh, key);
  };
  const float frame = 0.07f;
  if (f.door_face && u > f.door_u && u < f.door_u + f.door_w && v > 0.3f && v < 2.35f) {
    const float lu = u - f.door_u, lv = v - 0.3f;
    if (lu < frame || lu > f.door_w - frame || lv > 2.05f - frame) {
      out = f.frame_colour * 0.8f;
      return true;
    }
    Vec3f d = Vec3f(0.30f, 0.20f, 0.12f) * (0.8f + 0.5f * hashf(sd, 7, 7));
    if (lv > 1.1f && lv < 1.8f && lu > 0.2f && lu < f.door_w - 0.2f) d = glass(lu, lv, f.door_w, 2.0f, 999);
    if (std::abs(lu - (f.door_w - 0.22f)) < 0.03f && std::abs(lv - 1.0f) < 0.12f) d = grey(0.8f);
    out = d;
    return true;
  }
  if (f.shop && u > 0.8f && u < f.length - 0.8f) {
    const float top = f.ground_h - 0.7f;
    if (v > top && v < top + 0.5f) {  // sign band with lettering
      const float shopHue = hashf(sd, 31, 1);
      Vec3f band = shopHue < 0.33f ? Vec3f(0.1f, 0.15f, 0.5f)
                                   : (shopHue < 0.66f ? Vec3f(0.55f, 0.08f, 0.06f) : Vec3f(0.1f, 0.35f, 0.15f));
      const float letter = ffloor((u - 0.8f) / 0.32f);
      const float lu = fract((u - 0.8f) / 0.32f), lv = (v - top) / 0.5f;
      if (lv > 0.2f && lv < 0.8f && lu > 0.15f && lu < 0.8f &&
          hashf(sd, static_cast<std::uint32_t>(static_cast<int>(letter)), 32) < 0.8f) {
        const float cellx = ffloor(lu * 3), celly = ffloor(lv * 5);
        if (hashf(sd, static_cast<std::uint32_t>(static_cast<int>(letter * 16 + cellx)),
                  static_cast<std::uint32_t>(static_cast<int>(celly))) < 0.6f)
          band = grey(0.92f);
      }
      out = band;
      return true;
    }
    if (v > 0.45f && v < top - 0.05f) {
      const float bay = 2.4f;
      const float lu = fract(u / bay) * bay;
      if (lu < 0.09f) {
        out = f.frame_colour * 0.7f;
        return true;
      }
      out = glass(lu, v - 0.45f, bay, top - 0.5f, static_cast<std::uint32_t>(static_cast<int>(ffloor(u / bay))) + 500u);
      return true;
    }
    out = facadeWall(f, u, v, fp);
    return true;
  }
  return false;
}

Vec3f facade(const Facade& f, float u, float v, float fp) {
  // The wall material, evaluated only where no opening or trim covers it.
  auto base = [&]() -> Vec3f { return facadeWall(f, u, v, fp); };
  const float style = hashf(static_cast<std::uint32_t>(f.building), 41, 42);
  Vec3f out;
  if (facadeTrim(f, u, v, fp, style, out)) return out;
  // Openings.
  auto glass = [&](float lu, float lv, float ww, float wh, std::uint32_t key) {
    return facadeGlass(f, u, v, fp, style, lu, lv, ww, wh, key);
  };
  const float frame = 0.07f;
  if (v < f.ground_h && facadeShopFront(f, u, v, fp, style, out)) return out;
  float lv, sill = f.win_sill;
  std::uint32_t fl;
  if (v < f.ground_h) {
    lv = v;
    sill = 1.1f;
    fl = 0;
    if (sill + f.win_h > f.ground_h - 0.4f) return base();
  } else {
    const float fi = ffloor((v - f.ground_h) / f.floor_h);
    lv = v - f.ground_h - fi * f.floor_h;
    fl = static_cast<std::uint32_t>(static_cast<int>(fi)) + 1;
  }
  const float ci = ffloor((u - f.col_offset) / f.col_spacing);
  const float lu = u - f.col_offset - ci * f.col_spacing - (f.col_spacing - f.win_w) * 0.5f;
  const float wu0 = f.col_offset + ci * f.col_spacing + (f.col_spacing - f.win_w) * 0.5f;
  if (wu0 < 0.5f || wu0 + f.win_w > f.length - 0.5f) return base();
  if (f.door_face && v < f.ground_h && wu0 + f.win_w > f.door_u - 0.3f && wu0 < f.door_u + f.door_w + 0.3f)
    return base();
  const float wv = lv - sill;
  // String course between floors.
  if (style > 0.3f && fl > 0 && lv < 0.16f)
    return f.trim_colour * (1.2f + 0.3f * detail(u, v, 0.01f, 3, fp, 5.f)) *
           (1.f - 0.35f * lineCov(lv - 0.08f, 0.015f, fp));
  // Lintel above the window, shutters beside it.
  if (lu >= -0.12f && lu <= f.win_w + 0.12f && wv > f.win_h && wv < f.win_h + 0.16f) return f.trim_colour * 1.15f;
  if (style > 0.65f && wv >= 0 && wv <= f.win_h &&
      ((lu < 0 && lu > -0.45f * f.win_w) || (lu > f.win_w && lu < 1.45f * f.win_w))) {
    const float hue = hashf(static_cast<std::uint32_t>(f.building), 44, 45);
    const Vec3f sh = hue < 0.5f ? Vec3f(0.15f, 0.35f, 0.2f) : Vec3f(0.45f, 0.3f, 0.18f);
    const float fl2 = fract(wv / 0.06f);
    return sh * (1.f - 0.45f * lineCov(std::min(fl2, 1.f - fl2) * 0.06f, 0.015f, fp)) *
           (1.f - 0.5f * lineCov(std::min(std::abs(lu), std::abs(lu - f.win_w)), 0.03f, fp));
  }
  if (lu >= -0.1f && lu <= f.win_w + 0.1f && wv >= -0.1f && wv < 0.f) return f.trim_colour * 1.25f;  // sill
  if (lu < 0 || lu > f.win_w || wv < 0 || wv > f.win_h) return base();
  if (lu < frame || lu > f.win_w - frame || wv < frame || wv > f.win_h - frame) return f.frame_colour;
  const std::uint32_t key = fl * 1000u + static_cast<std::uint32_t>(static_cast<int>(ci) + 500);
  return glass(lu - frame, wv - frame, f.win_w - 2 * frame, f.win_h - 2 * frame, key);
}

Vec3f leaves(int param, float u, float v, float fp) {
  const float o = static_cast<float>(param % 997) * 0.031f;
  const float clumps = N(u / 3.f + o, v / 3.f);
  float t = 0.4f + 0.5f * (clumps - 0.5f) + 0.8f * detail(u, v, 0.05f, 3, fp, o) + 0.8f * speckle(u, v, 0.06f, fp, 31) +
            0.7f * speckle(u, v, 0.16f, fp, 32) + 0.5f * speckle(u, v, 0.45f, fp, 33);
  t = std::clamp(t, 0.f, 1.1f);
  const float hue = hashf(static_cast<std::uint32_t>(param), 1, 2);
  const Vec3f dark(0.04f, 0.1f + 0.05f * hue, 0.04f), light(0.5f + 0.2f * hue, 0.8f, 0.3f);
  return mix(dark, light, t);
}

Vec3f sign(const SignStyle& s, float u, float v, float fp) {
  (void)fp;
  const float r = std::hypot(u, v);
  switch (s.kind) {
    case 0: {  // speed limit
      if (r > 0.32f) return grey(0.5f);
      if (r > 0.25f) return Vec3f(0.75f, 0.08f, 0.07f);
      if (std::abs(v) < 0.1f && std::abs(u) < 0.14f) {
        const float d = ffloor((u + 0.14f) / 0.14f);
        const float lu = fract((u + 0.14f) / 0.14f), lv = (v + 0.1f) / 0.2f;
        const bool ring = lu < 0.25f || lu > 0.75f || lv < 0.18f || lv > 0.82f;
        if (ring && hashf(s.seed, static_cast<std::uint32_t>(static_cast<int>(d)),
                          static_cast<std::uint32_t>(static_cast<int>(lv * 3))) < 0.85f)
          return grey(0.05f);
      }
      return grey(0.92f);
    }
    case 1:  // blue mandatory
      if (r > 0.32f) return grey(0.5f);
      if ((std::abs(u) < 0.05f && v > -0.2f && v < 0.12f) ||
          (v > 0.05f && std::abs(u) < 0.2f - (v - 0.05f) * 1.3f && v < 0.2f))
        return grey(0.95f);
      return Vec3f(0.12f, 0.25f, 0.65f);
    case 2: {  // warning triangle
      const float y = v + 0.2f;
      if (y < 0 || std::abs(u) > 0.32f - y * 0.55f) return grey(0.5f);
      if (y < 0.07f || std::abs(u) > 0.25f - y * 0.55f) return Vec3f(0.78f, 0.08f, 0.08f);
      if (std::abs(u) < 0.03f && y > 0.12f && y < 0.32f) return grey(0.05f);
      return grey(0.93f);
    }
    case 3:  // parking
      if (std::abs(u) > 0.3f || std::abs(v) > 0.3f) return grey(0.5f);
      if (std::abs(u) > 0.27f || std::abs(v) > 0.27f) return grey(0.95f);
      if ((u > -0.12f && u < -0.04f && std::abs(v) < 0.18f) ||
          (std::hypot(u - 0.02f, v - 0.07f) < 0.11f && std::hypot(u - 0.02f, v - 0.07f) > 0.04f && u > -0.05f))
        return grey(0.95f);
      return Vec3f(0.1f, 0.3f, 0.7f);
    default: {  // green direction sign with text blocks
      const float ch = ffloor(u / 0.09f), ln = ffloor(v / 0.16f);
      const float lu = fract(u / 0.09f), lv = fract(v / 0.16f);
      if (lu > 0.15f && lu < 0.8f && lv > 0.2f && lv < 0.8f &&
          hashf(s.seed, static_cast<std::uint32_t>(static_cast<int>(ch) + 100),
                static_cast<std::uint32_t>(static_cast<int>(ln) + 100)) < 0.55f)
        return grey(0.95f);
      return Vec3f(0.05f, 0.4f, 0.2f);
    }
  }
}

Vec3f car(const World& w, std::uint16_t m, int param, float u, float v, float fp) {
  const bool tread = param < 0;
  const CarStyle& s = w.car_styles[tread ? -1 - param : param];
  const float paintNoise = 0.06f * (N(u / 2.f + static_cast<float>(s.seed % 71) * 0.01f, v / 2.f) - 0.5f);
  const Vec3f paint = s.colour * (0.92f + paintNoise + 0.12f * s.metallic * (N(u / 0.7f, v / 0.7f) - 0.5f));
  switch (m) {
    case M_CAR_BODY: {
      // Side: (x, z). Door seams, crease, handles, dirt near the sills.
      Vec3f c = paint;
      const float xd = 0.5f * (s.x_wb + s.x_rr);
      if ((std::abs(u - (s.x_wb - 0.05f)) < 0.012f || std::abs(u - xd) < 0.012f) && v > 0.35f && v < s.hb) c *= 0.45f;
      if (std::abs(v - (s.hb - 0.14f)) < 0.01f) c *= 0.75f;
      if (std::abs(v - (s.hb - 0.2f)) < 0.025f &&
          (std::abs(u - (xd + 0.25f)) < 0.1f || std::abs(u - (s.x_rr + 0.3f)) < 0.1f))
        c = grey(0.15f);
      if (v < 0.4f) c = mix(c, grey(0.18f), 0.4f * (0.4f - v) / 0.4f + 0.2f * N(u, v));
      return c;
    }
    case M_CAR_CABIN: {
      // Cabin side in (x, z): windows inset from the trapezoid, B pillar.
      const float z0 = s.hb + 0.06f, z1 = s.h - 0.06f;
      if (v > z0 && v < z1) {
        const float t = (v - s.hb) / (s.h - s.hb);
        const float xf = s.x_wb + (s.x_rf - s.x_wb) * t - 0.08f, xr = s.x_rb + (s.x_rr - s.x_rb) * t + 0.08f;
        const float xb = 0.5f * (s.x_wb + s.x_rr);
        if (u < xf && u > xr && std::abs(u - xb) > 0.05f) {
          const float refl = 0.08f + 0.25f * t + 0.12f * N(u / 3.f + 0.2f, v / 3.f);
          return Vec3f(refl * 0.9f, refl * 0.95f, refl * 1.05f);
        }
        return grey(0.06f);
      }
      return paint;
    }
    case M_CAR_GLASS: {
      const float t = std::clamp(std::abs(v) / (s.w * 0.45f), 0.f, 1.f);
      if (t > 0.9f) return grey(0.05f);
      const float refl = 0.07f + 0.12f * u + 0.1f * N(u / 2.f, v / 2.f + 0.5f);
      return Vec3f(refl, refl * 1.05f, refl * 1.15f);
    }
    case M_CAR_FRONT: {
      const float a = std::abs(v);
      const float len = s.hb - 0.18f - (s.wheel_r * 0.55f + 0.15f);
      if (u > len - 0.22f && a > s.w / 2 - 0.45f && a < s.w / 2 - 0.08f)
        return grey(0.85f) + Vec3f(0, 0.02f, 0.05f) * N(u * 5, v * 5);
      if (u > 0.04f && u < 0.16f && a < 0.26f) {
        const float ch = ffloor((v + 0.26f) / 0.065f);
        if (a < 0.22f && u > 0.06f && u < 0.14f && fract((v + 0.26f) / 0.065f) < 0.65f &&
            hashf(static_cast<std::uint32_t>(s.plate_seed), static_cast<std::uint32_t>(static_cast<int>(ch)),
                  static_cast<std::uint32_t>(static_cast<int>((u - 0.06f) / 0.027f))) < 0.6f)
          return grey(0.08f);
        return grey(0.9f);
      }
      if (u > 0.2f && u < len - 0.25f && a < s.w / 2 - 0.5f)
        return grey(0.08f + 0.1f * (fract(u / 0.04f) < 0.5f ? 1.f : 0.f) * fade(0.02f, fp));
      return paint;
    }
    case M_CAR_REAR: {
      const float a = std::abs(v);
      if (u > 0.04f && u < 0.24f && a > s.w / 2 - 0.4f && a < s.w / 2 - 0.06f)
        return Vec3f(0.65f, 0.05f, 0.05f) * (0.8f + 0.3f * (fract(u / 0.05f) < 0.5f ? 1.f : 0.f));
      if (u > 0.26f && u < 0.38f && a < 0.26f) {
        const float ch = ffloor((v + 0.26f) / 0.065f);
        if (a < 0.22f && u > 0.28f && u < 0.36f && fract((v + 0.26f) / 0.065f) < 0.65f &&
            hashf(static_cast<std::uint32_t>(s.plate_seed), static_cast<std::uint32_t>(static_cast<int>(ch) + 50),
                  static_cast<std::uint32_t>(static_cast<int>((u - 0.28f) / 0.027f))) < 0.6f)
          return grey(0.08f);
        return grey(0.9f);
      }
      return paint;
    }
    case M_TYRE: {
      if (tread) return grey(0.06f + 0.04f * N(u * 3, v * 3));
      const float r = std::hypot(u, v) / s.wheel_r;
      if (r < 0.62f) {
        const float ang = std::atan2(v, u);
        const bool spoke = fract(ang / (2 * static_cast<float>(M_PI)) * 5 + 0.1f) < 0.28f;
        if (r < 0.15f) return grey(0.55f);
        return spoke || r > 0.55f ? grey(0.72f) : grey(0.12f);
      }
      return grey(0.07f + (r > 0.66f && r < 0.7f ? 0.05f : 0.f));
    }
    default:
      return paint;
  }
}

}  // namespace

float noiseTile(float u, float v) { return N(u, v); }

Vec3f shadeSurface(const World& w, const ShadeInput& in) {
  const float u = in.u, v = in.v, fp = in.footprint;
  switch (in.material) {
    case M_ROAD:
      return road(w, w.streets[in.param], u, v, fp);
    case M_ASPHALT:
      return asphalt(u, v, fp);
    case M_PAVEMENT:
      return pavement(u, v, fp);
    case M_KERB:
      return kerb(u, v, fp);
    case M_FACADE:
      return facade(w.facades[in.param], u, v, fp);
    case M_ROOF:
      return grey(0.25f + 0.1f * N(u / 10.f, v / 10.f));
    case M_BARK:
      return Vec3f(0.25f, 0.18f, 0.12f) *
             (0.8f + 0.5f * N(u / 0.5f, v / 4.f) + 0.8f * detail(u * 3.f, v, 0.02f, 3, fp, 4.f));
    case M_LEAVES:
      return leaves(in.param, u, v, fp);
    case M_POLE:
      return grey(0.42f + 0.1f * N(u / 2.f, v / 2.f));
    case M_SIGN:
      return sign(w.signs[in.param], u, v, fp);
    case M_SIGN_BACK:
      return grey(0.55f);
    case M_FENCE: {  // garden fence: pickets on two rails
      const float pu = fract(u / 0.14f);
      const float picket = lineCov(std::min(pu, 1.f - pu) * 0.14f, 0.07f, fp);
      const float rail = std::max(lineCov(v - 0.35f, 0.06f, fp), lineCov(v - 0.8f, 0.06f, fp));
      const Vec3f wood = Vec3f(0.55f, 0.42f, 0.3f) * (0.85f + 0.3f * N(u / 3.f, v / 3.f));
      return mix(mix(Vec3f(0.12f, 0.2f, 0.08f) * (1.f + 2.f * detail(u, v, 0.03f, 3, fp, 3.f)), wood, picket),
                 wood * 0.8f, rail);
    }
    case M_GRASS: {
      const float g = detail(u, v, 0.02f, 4, fp, 8.f) + 0.3f * speckle(u, v, 0.04f, fp, 9);
      const float dry = N(u / 40.f, v / 40.f);
      return mix(Vec3f(0.16f, 0.32f, 0.10f), Vec3f(0.42f, 0.42f, 0.2f), dry * 0.7f) * (0.9f + 1.0f * g);
    }
    case M_WALL: {
      float c = 0.55f + 0.3f * detail(u, v, 0.015f, 4, fp, 17.f);
      if (fract(u / 4.0f) < 0.02f) c *= 0.6f;
      if (fract(u / 0.3f) < 0.5f) c *= 1.0f - 0.12f * fade(0.15f, fp);
      const float graffiti = N(u / 12.f + 0.4f, v / 12.f);
      if (graffiti > 0.72f && v < 2.5f) return Vec3f(0.2f + graffiti * 0.5f, 0.1f, 0.5f - graffiti * 0.3f);
      return Vec3f(c, c * 0.98f, c * 0.94f);
    }
    case M_RAIL:
      return grey(0.6f + 0.15f * (fract(v / 0.12f) < 0.5f ? 1.f : 0.f) * fade(0.06f, fp) -
                  (fract(u / 2.0f) < 0.05f ? 0.3f : 0.f));
    case M_PED_SHIRT:
      return w.ped_styles[in.param].shirt * (0.85f + 0.3f * N(u * 2, v * 2));
    case M_PED_TROUSERS:
      return w.ped_styles[in.param].trousers * (0.85f + 0.3f * N(u * 2 + 0.5f, v * 2));
    case M_PED_SKIN:
      return w.ped_styles[in.param].skin;
    default:
      return car(w, in.material, in.param, u, v, fp);
  }
}

Vec3f shadeSky(const Eigen::Vector3f& d) {
  const float e = std::max(d.z(), 0.f);
  Vec3f c = mix(Vec3f(0.78f, 0.84f, 0.90f), Vec3f(0.42f, 0.60f, 0.86f), std::sqrt(e));
  if (d.z() > 0.01f) {
    const float k = 1.f / d.z();
    const float cl =
        N(d.x() * k * 0.35f + 0.3f, d.y() * k * 0.35f) * 0.7f + 0.3f * N(d.x() * k * 1.4f, d.y() * k * 1.4f + 0.2f);
    const float cover = std::clamp((cl - 0.5f) * 3.f, 0.f, 1.f);
    c = mix(c, Vec3f(0.93f, 0.93f, 0.95f) * (0.85f + 0.15f * cl), cover * std::min(1.f, e * 6.f));
  }
  return c;
}

float lidarReflectance(std::uint16_t m) {
  switch (m) {
    case M_ROAD:
    case M_ASPHALT:
      return 0.22f;
    case M_PAVEMENT:
    case M_KERB:
      return 0.35f;
    case M_FACADE:
      return 0.4f;
    case M_LEAVES:
      return 0.3f;
    case M_BARK:
      return 0.25f;
    case M_POLE:
    case M_RAIL:
      return 0.6f;
    case M_SIGN:
      return 0.95f;
    case M_GRASS:
      return 0.3f;
    case M_CAR_GLASS:
      return 0.05f;
    case M_TYRE:
      return 0.08f;
    case M_CAR_REAR:
    case M_CAR_FRONT:
      return 0.7f;
    default:
      return 0.45f;
  }
}

}  // namespace beslam::sim::detail
