// The synthetic street (synthetic.h): its world, route and rendering.
// Over 600 lines: the renderer's shading helpers are shared by the world and
// the rendering under one floating-point contraction setting (the pragmas
// below), which keeps every frame bit-identical on every compiler; split over
// two files, each would need the setting kept in step.
#include "synthetic/synthetic.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "internal/check.h"
#include "lsgd/error.h"
#include "lsgd/eval/groundtruth.h"

// Frames must be bit-identical on every platform: forbid fusing a * b + c into
// one FMA instruction (which rounds once instead of twice). With that, the
// renderer uses only IEEE-exact operations (+ - * / sqrt floor conversions).
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

namespace lsgd::eval {
namespace {

// ---- world constants (world units are about metres) ----------------------
constexpr double kPi = 3.14159265358979323846;
constexpr double kFacadeX = 5.0;                  // facades stand at x = -5 and x = +5
constexpr double kRoadHalf = 3.2;                 // road |x| < 3.2, sidewalks beyond
constexpr double kCameraX = 1.3;                  // the camera drives in the right lane
constexpr double kCameraHeight = 1.5;             // above the ground
constexpr double kFogDistance = 30.0;             // contrast falls to 1/e at this distance
constexpr double kMaxDepth = 400.0;               // rays are cut here
constexpr double kRegionGap = 60.0;               // empty street between two new regions
constexpr double kWorldMargin = 80.0;             // facades generated before s = 0
constexpr float kFog[3] = {150.f, 146.f, 140.f};  // BGR colour distance fades to

// ---- deterministic randomness: splitmix64 finaliser ----------------------
std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
std::uint64_t hash(std::uint64_t a, std::uint64_t b) { return mix(a ^ mix(b)); }
std::uint64_t hash(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return hash(hash(a, b), c);
}
// One-mix hash of a 2-D lattice point, for the per-pixel hot paths.
std::uint64_t lattice(std::uint64_t key, std::uint64_t x, std::uint64_t y) {
  return mix(key ^ (x * 0xD1B54A32D192ED03ull) ^ (y * 0xAEF17502108EF2D9ull));
}
// Uniform in [0, 1) from the top 53 bits.
double unit(std::uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }
double uniform(std::uint64_t h, double lo, double hi) { return lo + (hi - lo) * unit(h); }
std::uint64_t cell(double v) {
  return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v)));
}
// v modulo period, in [0, period), also for negative v.
double wrap(double v, double period) { return v - std::floor(v / period) * period; }

// Smooth value noise in [0, 1): bilinear with smoothstep between hashed lattice values.
double value_noise(std::uint64_t key, double x, double y) {
  const double fx = std::floor(x), fy = std::floor(y);
  const std::uint64_t ix = cell(fx), iy = cell(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const double v00 = unit(lattice(key, ix, iy)), v10 = unit(lattice(key, ix + 1, iy));
  const double v01 = unit(lattice(key, ix, iy + 1)), v11 = unit(lattice(key, ix + 1, iy + 1));
  const double top = v00 + (v10 - v00) * tx, bottom = v01 + (v11 - v01) * tx;
  return top + (bottom - top) * ty;
}

// sin(x) by range reduction and a Taylor polynomial (error < 1e-7): libm's
// sin may differ between platforms in the last bit, this does not.
double det_sin(double x) {
  x -= 2 * kPi * std::floor((x + kPi) / (2 * kPi));  // [-pi, pi)
  if (x > kPi / 2) x = kPi - x;
  if (x < -kPi / 2) x = -kPi - x;  // [-pi/2, pi/2]
  const double x2 = x * x;
  return x * (1 - x2 / 6 * (1 - x2 / 20 * (1 - x2 / 42 * (1 - x2 / 72 * (1 - x2 / 110)))));
}
double det_cos(double x) { return det_sin(x + kPi / 2); }

// exp(-a) for a >= 0, a smooth rational stand-in for the fog falloff.
double fog_weight(double a) {
  return 1.0 / (1.0 + a * (1.0 + a * (0.5 + a * (1.0 / 6.0 + a / 24.0))));
}

struct Rgb {
  float b = 0, g = 0, r = 0;
};
// Gray level g tinted by (tb, tg, tr).
Rgb tinted(double g, const double tint[3]) {
  return {static_cast<float>(g * tint[0]), static_cast<float>(g * tint[1]),
          static_cast<float>(g * tint[2])};
}

// ---- route ----------------------------------------------------------------
enum class Light { kDay, kDim, kBright };
enum class Traffic { kNone, kSome, kDense };  // moving objects on a stretch

// One stretch of the default route. A new stretch shows region `region` (new
// regions are laid out one after the other, kRegionGap apart); a revisit
// drives over the fraction [from, to] of an earlier region.
struct StretchSpec {
  int region;
  bool revisit;
  double length;  // world units at route_scale 1 (new stretches)
  double from, to;
  double speed;  // world units per frame
  Light light;
  Traffic traffic;
  const char* label;
};

// A to E came first and must keep their frames and ground truth: new
// stretches go at the end. F, G and H are new places under the conditions of
// the revisits (A' lighting; A'' lighting with objects; denser objects than
// anywhere else): a detector must find no loop there.
constexpr StretchSpec kRoute[] = {
    {0, false, 180, 0, 1, 1.00, Light::kDay, Traffic::kNone, "A: new street"},
    {1, false, 120, 0, 1, 1.00, Light::kDay, Traffic::kNone, "B: new street"},
    {0, true, 0, 10.0 / 180, 130.0 / 180, 0.90, Light::kDim, Traffic::kNone, "A': revisit of A"},
    {2, false, 100, 0, 1, 1.05, Light::kDay, Traffic::kSome, "C: new street"},
    {1, true, 0, 10.0 / 120, 110.0 / 120, 1.10, Light::kDay, Traffic::kSome, "B': revisit of B"},
    {3, false, 80, 0, 1, 1.00, Light::kDay, Traffic::kNone, "D: new street"},
    {0, true, 0, 80.0 / 180, 170.0 / 180, 0.95, Light::kBright, Traffic::kSome,
     "A'': revisit of A"},
    {4, false, 60, 0, 1, 1.00, Light::kDay, Traffic::kNone, "E: new street"},
    {5, false, 80, 0, 1, 1.00, Light::kDim, Traffic::kNone, "F: new street"},
    {6, false, 75, 0, 1, 1.05, Light::kBright, Traffic::kSome, "G: new street"},
    {7, false, 85, 0, 1, 1.00, Light::kDay, Traffic::kDense, "H: new street"},
};

void set_light(Light light, RouteSegment& seg) {
  if (light == Light::kDim) {  // overcast evening: darker, flatter, lit from the left
    seg.light_gain = 0.75, seg.light_offset = 15, seg.light_gradient_x = -24;
    seg.light_gradient_y = 10;
  } else if (light == Light::kBright) {  // brighter sun: a little more contrast
    seg.light_gain = 1.1, seg.light_offset = -8, seg.light_gradient_x = 10;
    seg.light_gradient_y = -6;
  }
}

std::string describe(const StretchSpec& spec, const RouteSegment& seg) {
  std::string label = spec.label;
  if (seg.light_gain != 1 || seg.light_offset != 0) {
    label += spec.light == Light::kDim ? ", dim lighting" : ", bright lighting";
  }
  if (seg.dense_objects) {
    label += ", dense moving objects";
  } else if (seg.moving_objects) {
    label += ", moving objects";
  }
  return label;
}

// ---- camera ---------------------------------------------------------------
struct Pose {
  double s = 0, x = 0, h = kCameraHeight;
  double sin_yaw = 0, cos_yaw = 1;  // yaw > 0 turns towards +x (right)
};

// The pose wobbles smoothly with s; each stretch has its own lateral offset,
// yaw bias and wobble phases, so two traverses of a place never coincide.
Pose camera_pose(std::uint64_t seed, int segment, bool revisit, double s) {
  const std::uint64_t key = hash(seed, 0xCA3E7A, static_cast<std::uint64_t>(segment));
  const double spread = revisit ? 0.6 : 0.15;
  Pose pose;
  pose.s = s;
  pose.x = kCameraX + uniform(hash(key, 1), -spread, spread) +
           0.2 * det_sin(2 * kPi * s / 37 + uniform(hash(key, 2), 0, 2 * kPi));
  const double degrees = uniform(hash(key, 3), -2.0, 2.0) +
                         1.2 * det_sin(2 * kPi * s / 23 + uniform(hash(key, 4), 0, 2 * kPi));
  const double yaw = degrees * kPi / 180;
  pose.sin_yaw = det_sin(yaw);
  pose.cos_yaw = det_cos(yaw);
  pose.h = kCameraHeight + 0.02 * det_sin(2 * kPi * s / 1.7);
  return pose;
}

// ---- facades --------------------------------------------------------------
// Everything that makes one building look like itself, derived from its key.
struct FacadeLook {
  double base, tint[3];
  int style;  // 0 panels, 1 window grid, 2 glass, 3 brick
  double detail_amp, detail_scale;
  double stripe_period, stripe_amp;
  double win_dx, win_w, win_floor, win_h, win_sill, win_level, win_jitter;
  double ground, shop_level, door_u, door_level;
  bool shop, sign;
  double sign_u0, sign_u1, sign_level, sign_tint[3];
};

void random_tint(std::uint64_t key, double strength, double tint[3]) {
  double sum = 0;
  for (int c = 0; c < 3; ++c) {
    tint[c] = 1 + uniform(hash(key, 40 + c), -strength, strength);
    sum += tint[c];
  }
  for (int c = 0; c < 3; ++c) tint[c] *= 3 / sum;
}

FacadeLook make_look(std::uint64_t key, int side) {
  FacadeLook f{};
  auto u = [&](int i, double lo, double hi) { return uniform(hash(key, i), lo, hi); };
  f.base = u(1, 45, 215) * (side == 0 ? 0.92 : 1.05);  // the sun is on the right facades
  random_tint(key, 0.22, f.tint);
  f.style = static_cast<int>(hash(key, 2) % 4);
  f.detail_amp = u(3, 4, 18), f.detail_scale = u(4, 0.25, 1.2);
  f.stripe_period = u(5, 0.5, 1.6), f.stripe_amp = f.style == 0 ? u(6, 8, 28) : 0;
  f.win_dx = f.style == 2 ? u(7, 1.2, 1.8) : u(7, 1.6, 3.0);
  f.win_w = f.style == 2 ? 0.9 : u(8, 0.35, 0.65);
  f.win_floor = u(9, 2.6, 3.4), f.win_h = f.style == 2 ? 0.9 : u(10, 0.4, 0.6);
  f.win_sill = (1 - f.win_h) * u(11, 0.3, 0.7);
  f.win_level = unit(hash(key, 12)) < 0.6 ? u(13, 20, 65) : u(13, 165, 240);
  if (f.style == 2) f.win_level = u(13, 90, 200);  // glass reflects the sky
  f.win_jitter = u(14, 5, 35);
  f.ground = u(15, 2.8, 3.8);
  f.shop = unit(hash(key, 16)) < 0.55, f.shop_level = u(17, 15, 80);
  f.door_u = u(18, 0.5, 3.5), f.door_level = u(19, 15, 120);
  f.sign = unit(hash(key, 20)) < 0.6;
  f.sign_u0 = u(21, 0.2, 1.5), f.sign_u1 = f.sign_u0 + u(22, 2.0, 6.0);
  f.sign_level = f.base < 130 ? u(23, 170, 250) : u(23, 10, 70);
  random_tint(hash(key, 24), 0.45, f.sign_tint);
  return f;
}

// Facade colour at distance u along building b (from its start) and height y.
Rgb shade_facade(const SyntheticWorld::Building& b, const FacadeLook& f, double u, double y) {
  double g = f.base;
  g += f.detail_amp * 2 * (value_noise(b.key, u / f.detail_scale, y / f.detail_scale) - 0.5);
  if (f.style == 3) {  // bricks 0.25 x 0.125, every other course shifted by half a brick
    const double course = std::floor(y * 8), along = u * 4 + 0.5 * wrap(course, 2);
    g += along - std::floor(along) < 0.08 || y * 8 - course < 0.12
             ? -18
             : 16 * (unit(lattice(b.key, cell(along), cell(course))) - 0.5);
  }
  if (f.stripe_amp > 0 && wrap(u, f.stripe_period) < 0.5 * f.stripe_period) g += f.stripe_amp;
  if (u < 0.12 || b.s1 - b.s0 - u < 0.12 || y > b.top - 0.35) g *= 0.68;  // edges, cornice
  if (y < f.ground) {
    if (f.sign && y > f.ground - 0.6 && y < f.ground - 0.1 && u > f.sign_u0 && u < f.sign_u1) {
      return tinted(f.sign_level, f.sign_tint);
    }
    if (u > f.door_u && u < f.door_u + 1.2 && y < 2.2) return tinted(f.door_level, f.tint);
    if (f.shop && y > 0.35 && y < f.ground - 0.75 && wrap(u, 3.0) > 0.45) {
      return tinted(f.shop_level + 0.3 * (g - f.base), f.tint);
    }
    return tinted(g, f.tint);
  }
  if (y < b.top - 0.7) {
    const double wu = wrap(u - 0.4, f.win_dx) / f.win_dx;
    const double level = (y - f.ground) / f.win_floor;
    const double wv = level - std::floor(level);
    if (wu < f.win_w && wv > f.win_sill && wv < f.win_sill + f.win_h) {
      const std::uint64_t id = hash(b.key, cell((u - 0.4) / f.win_dx), cell(level));
      return tinted(f.win_level + f.win_jitter * (2 * unit(id) - 1), f.tint);
    }
  }
  return tinted(g, f.tint);
}

// ---- ground and sky -------------------------------------------------------
constexpr double kAsphaltTint[3] = {1.04, 1.0, 0.96};
constexpr double kStoneTint[3] = {0.95, 1.0, 1.05};
constexpr double kSkyTint[3] = {1.15, 1.02, 0.85};

Rgb shade_sidewalk(std::uint64_t seed, double x, double s) {
  const double ax = std::fabs(x);
  if (ax < kRoadHalf + 0.15) return tinted(178, kStoneTint);  // kerb
  const double tx = x / 1.2, ts = s / 1.2;
  if (tx - std::floor(tx) < 0.05 || ts - std::floor(ts) < 0.05) return tinted(95, kStoneTint);
  const double g = 95 + 60 * value_noise(seed + 6, s / 30, 0.5) +
                   40 * unit(lattice(seed, cell(tx), cell(ts))) +
                   10 * (value_noise(seed + 7, x * 3, s * 3) - 0.5);
  return tinted(g, kStoneTint);
}

Rgb shade_road(std::uint64_t seed, double x, double s) {
  // Old and new asphalt alternate along the street (over tens of units).
  double g = 50 + 50 * value_noise(seed + 2, s / 25, 0.5) +
             36 * (value_noise(seed + 3, x * 0.5, s * 0.5) - 0.5) +
             12 * (unit(lattice(seed + 4, cell(x * 16), cell(s * 16))) - 0.5);  // grain
  // One hash per 20-unit block of road, sliced into 8-bit fields in [0, 1).
  const std::uint64_t block = lattice(seed ^ 0xB10C, cell(s / 20), 0);
  auto field = [block](int i) { return static_cast<double>((block >> (8 * i)) & 0xFF) / 256; };
  const double bs = wrap(s, 20);
  const double p0 = 12 * field(0), px = -3 + 4 * field(1);
  if (field(2) < 0.5 && bs > p0 && bs < p0 + 2 + 5 * field(3) && x > px &&
      x < px + 1 + 1.5 * field(4)) {
    g *= field(5) < 0.5 ? 0.6 : 1.35;  // patched asphalt
  }
  if (field(6) < 0.3 && bs > 14 && bs < 17.5 && wrap(x, 1.0) < 0.5) g = 212;  // crosswalk
  if (std::fabs(x) < 0.08 && wrap(s, 6) < 3) g = 205;                         // centre dashes
  if (std::fabs(std::fabs(x) - (kRoadHalf - 0.25)) < 0.06) g = 190;           // edge lines
  return tinted(g, kAsphaltTint);
}

Rgb shade_ground(std::uint64_t seed, double x, double s) {
  return std::fabs(x) < kRoadHalf ? shade_road(seed, x, s) : shade_sidewalk(seed, x, s);
}

// elevation: tangent of the ray's angle above the horizon.
Rgb shade_sky(double elevation) {
  return tinted(172 + 55 * std::min(elevation, 1.5) / 1.5, kSkyTint);
}

// ---- per-frame geometry -----------------------------------------------------
struct Camera {
  Pose pose;
  double focal = 0, cx = 0, cy = 0;
};

// The ray through one image column (per unit of upward slope it also rises).
struct Column {
  double dx = 0, dz = 0, norm2 = 0;  // horizontal ray direction and its squared length
  double t_wall = kMaxDepth;         // ray parameter at the facade
  double s_wall = 0;                 // street coordinate of the facade point
  const SyntheticWorld::Building* building = nullptr;
  FacadeLook look{};
};

const SyntheticWorld::Building& find_building(const std::vector<SyntheticWorld::Building>& row,
                                              double s) {
  auto it = std::upper_bound(row.begin(), row.end(), s,
                             [](double v, const SyntheticWorld::Building& b) { return v < b.s1; });
  return it == row.end() ? row.back() : *it;
}

Column make_column(const Camera& cam, const std::vector<SyntheticWorld::Building> (&rows)[2],
                   int u) {
  Column c;
  const double xc = (u + 0.5 - cam.cx) / cam.focal;
  c.dx = xc * cam.pose.cos_yaw + cam.pose.sin_yaw;
  c.dz = -xc * cam.pose.sin_yaw + cam.pose.cos_yaw;
  c.norm2 = c.dx * c.dx + c.dz * c.dz;
  const int side = c.dx < 0 ? 0 : 1;
  if (std::fabs(c.dx) > 1e-12) {
    c.t_wall = std::min(kMaxDepth, ((side ? kFacadeX : -kFacadeX) - cam.pose.x) / c.dx);
  }
  c.s_wall = cam.pose.s + c.t_wall * c.dz;
  c.building = &find_building(rows[side], c.s_wall);
  c.look = make_look(c.building->key, side);
  return c;
}

// Colour of the scene (before fog) seen at column c and upward slope yc, and
// the distance to it.
Rgb shade_ray(std::uint64_t seed, const Camera& cam, const Column& c, double yc, double* dist) {
  if (yc < 0) {
    const double t = cam.pose.h / -yc;
    if (t < c.t_wall) {
      *dist = t * std::sqrt(c.norm2 + yc * yc);
      return shade_ground(seed, cam.pose.x + t * c.dx, cam.pose.s + t * c.dz);
    }
  }
  const double y = cam.pose.h + c.t_wall * yc;
  if (y >= c.building->top) {
    *dist = 0;  // the sky is not fogged
    return shade_sky(yc / std::sqrt(c.norm2));
  }
  *dist = c.t_wall * std::sqrt(c.norm2 + yc * yc);
  return shade_facade(*c.building, c.look, c.s_wall - c.building->s0, y);
}

Rgb fogged(Rgb c, double dist) {
  const float w = static_cast<float>(fog_weight(dist / kFogDistance));
  return {kFog[0] + (c.b - kFog[0]) * w, kFog[1] + (c.g - kFog[1]) * w,
          kFog[2] + (c.r - kFog[2]) * w};
}

// ---- moving objects -------------------------------------------------------
constexpr std::int64_t kSpawnPeriod = 9;       // frames between two objects
constexpr std::int64_t kDenseSpawnPeriod = 3;  // the same on a stretch with dense objects
constexpr std::int64_t kLifetime = 45;         // frames an object exists

struct Mover {
  bool vehicle = false;
  double x = 0, s = 0;  // world position in the frame drawn
  double width = 0, height = 0;
  double stride = 0;  // walking phase, radians
  double tint[3] = {1, 1, 1};
  double level = 0, level2 = 0;  // shirt / body, trousers / windows
  double depth = 0, xc = 0;      // camera-frame depth and lateral position
};

// Object k of a stretch: spawned ahead of the camera at frame `spawn`,
// pedestrians cross the street, vehicles come down the left lane. `dense`
// (only on stretches with dense objects) makes them more often vehicles,
// larger (vans and buses, tall people) and spawned nearer, so they cover more
// of the view; without it the draws are those of the first version of the
// route, which keeps the frames of A to E unchanged.
Mover make_mover(std::uint64_t key, double spawn_place, std::int64_t age, bool dense) {
  Mover m;
  m.vehicle = unit(hash(key, 1)) < (dense ? 0.5 : 0.4);
  const double s0 =
      spawn_place + (dense ? uniform(hash(key, 2), 8, 26) : uniform(hash(key, 2), 14, 30));
  if (m.vehicle) {
    m.x = -1.6 + uniform(hash(key, 3), -0.2, 0.2);
    m.s = s0 - uniform(hash(key, 4), 0.2, 0.8) * static_cast<double>(age);
    if (dense) {
      m.width = uniform(hash(key, 5), 1.9, 2.5), m.height = uniform(hash(key, 6), 1.8, 3.2);
    } else {
      m.width = uniform(hash(key, 5), 1.7, 2.0), m.height = uniform(hash(key, 6), 1.4, 1.9);
    }
  } else {
    const double dir = unit(hash(key, 7)) < 0.5 ? -1 : 1;
    m.x = uniform(hash(key, 3), -4.6, 4.6) +
          dir * uniform(hash(key, 4), 0.04, 0.12) * static_cast<double>(age);
    m.s = s0;
    if (dense) {
      m.width = uniform(hash(key, 5), 0.6, 0.85), m.height = uniform(hash(key, 6), 1.7, 2.0);
    } else {
      m.width = uniform(hash(key, 5), 0.5, 0.65), m.height = uniform(hash(key, 6), 1.55, 1.9);
    }
    m.stride = 0.8 * static_cast<double>(age) + uniform(hash(key, 8), 0, 2 * kPi);
  }
  random_tint(hash(key, 9), 0.5, m.tint);
  m.level = uniform(hash(key, 10), 25, 235), m.level2 = uniform(hash(key, 11), 20, 90);
  return m;
}

// Colour of a mover at (a, b) in [0,1]^2 (a across, b up from the ground);
// false where it is transparent.
bool shade_mover(const Mover& m, double a, double b, Rgb* out) {
  static constexpr double kSkin[3] = {0.8, 0.95, 1.2};
  static constexpr double kGray[3] = {1, 1, 1};
  if (m.vehicle) {
    if (b < 0.16) {
      if ((a > 0.06 && a < 0.26) || (a > 0.74 && a < 0.94)) return *out = tinted(22, kGray), true;
      return false;
    }
    if (b < 0.6) {
      const bool lamp = b > 0.4 && b < 0.5 && (a < 0.14 || a > 0.86);
      return *out = lamp ? tinted(240, kGray) : tinted(m.level, m.tint), true;
    }
    const double inset = 0.1 + (b - 0.6) * 0.3;
    if (b > 0.98 || a < inset || a > 1 - inset) return false;
    const bool frame = b > 0.93 || a < inset + 0.04 || a > 1 - inset - 0.04;
    return *out = frame ? tinted(m.level, m.tint) : tinted(m.level2, kGray), true;
  }
  if (b > 0.86) {
    const double ea = (a - 0.5) / 0.17, eb = (b - 0.93) / 0.07;
    if (ea * ea + eb * eb > 1) return false;
    return *out = tinted(150, kSkin), true;
  }
  if (b > 0.46) {
    if (a < 0.1 || a > 0.9) return false;
    return *out = tinted(m.level, m.tint), true;
  }
  const double swing = 0.08 * det_sin(m.stride);
  const bool leg = (a > 0.2 + swing && a < 0.46 + swing) || (a > 0.54 - swing && a < 0.8 - swing);
  if (!leg) return false;
  return *out = tinted(m.level2, kGray), true;
}

}  // namespace

// ---- options ----------------------------------------------------------------
void SyntheticOptions::check() const {
  internal::check_range("synthetic.width", width, 32, 4096, "pixels");
  internal::check_range("synthetic.height", height, 32, 4096, "pixels");
  internal::check_range("synthetic.route_scale", route_scale, 0.1, 10.0);
  internal::check_range_open_low("synthetic.loop_radius", loop_radius, 0.0, 30.0, "world units");
  internal::check_range("synthetic.sensor_noise", sensor_noise, 0.0, 64.0, "gray levels");
  internal::check_range("synthetic.field_of_view", field_of_view, 30.0, 150.0, "degrees");
}

// ---- world ------------------------------------------------------------------
SyntheticWorld::SyntheticWorld(const SyntheticOptions& options) : options_(options) {
  options_.check();
  build_route();
  build_world();
  build_ground_truth();
}

void SyntheticWorld::build_route() {
  std::vector<double> region_begin, region_length;
  double next_region = 0;
  for (const StretchSpec& spec : kRoute) {
    RouteSegment seg;
    if (!spec.revisit) {
      region_begin.push_back(next_region);
      region_length.push_back(spec.length * options_.route_scale);
      next_region += region_length.back() + kRegionGap;
    }
    const double begin = region_begin[spec.region], length = region_length[spec.region];
    seg.s_begin = begin + spec.from * length;
    seg.s_end = begin + spec.to * length;
    const auto n = std::max<std::int64_t>(2, std::llround((seg.s_end - seg.s_begin) / spec.speed));
    seg.step = (seg.s_end - seg.s_begin) / static_cast<double>(n - 1);
    seg.first_frame = frames();
    seg.last_frame = seg.first_frame + n - 1;
    seg.revisit = spec.revisit;
    seg.moving_objects = spec.traffic != Traffic::kNone && options_.moving_objects;
    seg.dense_objects = spec.traffic == Traffic::kDense && options_.moving_objects;
    if (options_.lighting_change) set_light(spec.light, seg);
    seg.label = describe(spec, seg);
    for (std::int64_t k = 0; k < n; ++k) {
      places_.push_back(k == n - 1 ? seg.s_end : seg.s_begin + static_cast<double>(k) * seg.step);
      segment_index_.push_back(static_cast<int>(route_.size()));
    }
    route_.push_back(seg);
  }
}

// Facades on both sides: buildings 5-16 units long, 4.5-18 high, with an
// occasional low wall (a gap between buildings) that lets the sky show.
void SyntheticWorld::build_world() {
  const double end = *std::max_element(places_.begin(), places_.end()) + kMaxDepth + 50;
  for (int side = 0; side < 2; ++side) {
    double s = -kWorldMargin;
    for (std::uint64_t i = 0; s < end; ++i) {
      Building b;
      b.key = hash(options_.seed, 0xFACADE + static_cast<std::uint64_t>(side), i);
      b.s0 = s;
      b.s1 = s + uniform(hash(b.key, 100), 5, 16);
      b.top = unit(hash(b.key, 101)) < 0.12 ? uniform(hash(b.key, 102), 1.8, 2.8)
                                            : uniform(hash(b.key, 102), 4.5, 18);
      buildings_[side].push_back(b);
      s = b.s1;
    }
  }
}

// Exact ground truth: every pair of frames whose places differ by at most
// loop_radius, found by a sweep over the frames sorted by place.
void SyntheticWorld::build_ground_truth() {
  ground_truth_ = GroundTruth(frames());
  std::vector<std::int64_t> order(places_.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::int64_t>(i);
  std::stable_sort(order.begin(), order.end(), [&](std::int64_t a, std::int64_t b) {
    return places_[static_cast<std::size_t>(a)] < places_[static_cast<std::size_t>(b)];
  });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const double s = places_[static_cast<std::size_t>(order[i])];
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      if (places_[static_cast<std::size_t>(order[j])] - s > options_.loop_radius) break;
      ground_truth_.add(order[i], order[j]);
    }
  }
}

void SyntheticWorld::check_frame(std::int64_t frame) const {
  if (frame < 0 || frame >= frames()) {
    internal::throw_invalid("synthetic frame ", frame, " is outside [0, ", frames(), ")");
  }
}

double SyntheticWorld::place(std::int64_t frame) const {
  check_frame(frame);
  return places_[static_cast<std::size_t>(frame)];
}

int SyntheticWorld::segment_of(std::int64_t frame) const {
  check_frame(frame);
  return segment_index_[static_cast<std::size_t>(frame)];
}

// ---- rendering --------------------------------------------------------------
namespace {

// Draws the movers alive in `frame` of stretch `seg` over the colour buffer,
// far to near.
void draw_movers(const SyntheticWorld& world, int seg_index, std::int64_t frame, const Camera& cam,
                 std::vector<Rgb>& image) {
  const RouteSegment& seg = world.route()[static_cast<std::size_t>(seg_index)];
  const SyntheticOptions& opt = world.options();
  std::vector<Mover> movers;
  const std::int64_t period = seg.dense_objects ? kDenseSpawnPeriod : kSpawnPeriod;
  const std::int64_t age0 = frame - seg.first_frame;
  for (std::int64_t k = std::max<std::int64_t>(0, (age0 - kLifetime) / period - 1);
       k <= age0 / period; ++k) {
    const std::uint64_t key = hash(opt.seed, 0x0B1EC7 + static_cast<std::uint64_t>(seg_index),
                                   static_cast<std::uint64_t>(k));
    const std::int64_t spawn = seg.first_frame + k * period + static_cast<std::int64_t>(key % 5);
    if (spawn > frame || spawn > seg.last_frame || frame - spawn > kLifetime) continue;
    Mover m = make_mover(key, world.place(spawn), frame - spawn, seg.dense_objects);
    const double rx = m.x - cam.pose.x, rz = m.s - cam.pose.s;
    m.xc = rx * cam.pose.cos_yaw - rz * cam.pose.sin_yaw;
    m.depth = rx * cam.pose.sin_yaw + rz * cam.pose.cos_yaw;
    if (m.depth > 1.0 && m.depth < 60.0) movers.push_back(m);
  }
  std::sort(movers.begin(), movers.end(),
            [](const Mover& a, const Mover& b) { return a.depth > b.depth; });
  for (const Mover& m : movers) {
    const double scale = cam.focal / m.depth;
    const double left = cam.cx + (m.xc - m.width / 2) * scale, w = m.width * scale;
    const double bottom = cam.cy + cam.pose.h * scale, h = m.height * scale;
    const int u0 = std::max(0, static_cast<int>(std::floor(left)));
    const int u1 = std::min(opt.width - 1, static_cast<int>(std::ceil(left + w)));
    const int v0 = std::max(0, static_cast<int>(std::floor(bottom - h)));
    const int v1 = std::min(opt.height - 1, static_cast<int>(std::ceil(bottom)));
    for (int v = v0; v <= v1; ++v) {
      const double b = (bottom - (v + 0.5)) / h;
      for (int u = u0; u <= u1; ++u) {
        const double a = (u + 0.5 - left) / w;
        Rgb c;
        if (a < 0 || a > 1 || b < 0 || b > 1 || !shade_mover(m, a, b, &c)) continue;
        image[static_cast<std::size_t>(v) * opt.width + u] = fogged(c, m.depth);
      }
    }
  }
}

// Applies the stretch's lighting (flickering +-2 % per frame) and sensor
// noise, and writes 8-bit BGR.
void expose(const SyntheticOptions& opt, const RouteSegment& seg, std::int64_t frame,
            const std::vector<Rgb>& image, cv::Mat& out) {
  const auto f = static_cast<std::uint64_t>(frame);
  const double gain = seg.light_gain * (1 + 0.02 * (2 * unit(hash(opt.seed, 0xF11C, f)) - 1));
  const double noise = opt.sensor_noise / 65535.0;
  const std::uint64_t frame_key = hash(opt.seed, 0x5E5502, f);
  for (int v = 0; v < opt.height; ++v) {
    auto* row = out.ptr<std::uint8_t>(v);
    const double gy = seg.light_gradient_y * ((v + 0.5) / opt.height - 0.5);
    for (int u = 0; u < opt.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * opt.width + u;
      const std::uint64_t h = lattice(frame_key, i, 0);
      const double n = noise * (static_cast<double>(h & 0xFFFF) +
                                static_cast<double>((h >> 16) & 0xFFFF) - 65535.0);
      const double add =
          seg.light_offset + gy + seg.light_gradient_x * ((u + 0.5) / opt.width - 0.5) + n;
      const float ch[3] = {image[i].b, image[i].g, image[i].r};
      for (int c = 0; c < 3; ++c) {
        const double x = std::floor(gain * ch[c] + add + 0.5);
        row[3 * u + c] = static_cast<std::uint8_t>(std::clamp(x, 0.0, 255.0));
      }
    }
  }
}

}  // namespace

cv::Mat SyntheticWorld::render(std::int64_t frame) const {
  check_frame(frame);
  const int seg_index = segment_index_[static_cast<std::size_t>(frame)];
  const RouteSegment& seg = route_[static_cast<std::size_t>(seg_index)];
  const int width = options_.width, height = options_.height;
  Camera cam;
  cam.pose = camera_pose(options_.seed, seg_index, seg.revisit, place(frame));
  const double half_fov = options_.field_of_view * kPi / 360;
  cam.focal = 0.5 * width * det_cos(half_fov) / det_sin(half_fov);
  cam.cx = 0.5 * width, cam.cy = 0.5 * height;

  std::vector<Column> columns(static_cast<std::size_t>(width));
  for (int u = 0; u < width; ++u)
    columns[static_cast<std::size_t>(u)] = make_column(cam, buildings_, u);
  std::vector<Rgb> image(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    const double yc = (cam.cy - v - 0.5) / cam.focal;
    for (int u = 0; u < width; ++u) {
      double dist = 0;
      const Rgb c = shade_ray(options_.seed, cam, columns[static_cast<std::size_t>(u)], yc, &dist);
      image[static_cast<std::size_t>(v) * width + u] = fogged(c, dist);
    }
  }
  if (seg.moving_objects) draw_movers(*this, seg_index, frame, cam, image);
  cv::Mat out(height, width, CV_8UC3);
  expose(options_, seg, frame, image, out);
  return out;
}

void write_synthetic_dataset(const SyntheticWorld& world, const std::string& dir) {
  namespace fs = std::filesystem;
  const fs::path root(dir);
  std::error_code ec;
  fs::create_directories(root / "images", ec);
  if (ec) throw IoError("cannot create '" + (root / "images").string() + "': " + ec.message());
  std::ofstream list(root / "sequence.txt");
  if (!list) throw IoError("cannot write '" + (root / "sequence.txt").string() + "'");
  for (std::int64_t i = 0; i < world.frames(); ++i) {
    std::ostringstream name;
    name << "images/" << std::setw(6) << std::setfill('0') << i << ".png";
    const fs::path file = root / name.str();
    if (!cv::imwrite(file.string(), world.render(i))) {
      throw IoError("cannot write image '" + file.string() + "'");
    }
    list << name.str() << '\n';
  }
  list.close();
  if (!list) throw IoError("cannot write '" + (root / "sequence.txt").string() + "'");
  write_pairs(world.ground_truth(), (root / "groundtruth.txt").string());
}

}  // namespace lsgd::eval
