// Camera descriptions, image sizes, cutting planes and palettes: what the
// render command parses, with its errors.

#include "geometry/error.h"
#include "geometry/organ_table.h"
#include "geometry/render/camera.h"
#include "geometry/render/cutting_planes.h"
#include "geometry/render/palette.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cmath>

namespace vox {
namespace {

const Eigen::Vector3d kLo(0, 0, 0), kHi(400, 200, 1600);
const Eigen::Vector3d kCentre(200, 100, 800);

TEST(RenderCamera, DefaultOrbitLooksAtTheBoxCentreFromMinusYAndFitsTheBox) {
  const Camera c = parseCamera("", kLo, kHi, 640, 480);
  EXPECT_TRUE(c.target.isApprox(kCentre));
  EXPECT_NEAR(c.eye[0], 200.0, 1e-9);
  EXPECT_NEAR(c.eye[2], 800.0, 1e-9);
  EXPECT_LT(c.eye[1], 100.0);
  // The box's corners project inside the frame, the tallest one onto the
  // margin: the 1600 mm box fills the frame's height.
  const CameraRays rays = cameraRays(c);
  double widest = 0.0, tallest = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner((k & 1) ? kHi.x() : kLo.x(), (k & 2) ? kHi.y() : kLo.y(), (k & 4) ? kHi.z() : kLo.z());
    const Eigen::Vector3d d = corner - rays.eye;
    const double depth = d.dot(rays.forward);
    widest = std::max(widest, std::abs(d.dot(rays.right)) / depth / (rays.tanHalfFovY * rays.aspect));
    tallest = std::max(tallest, std::abs(d.dot(rays.up)) / depth / rays.tanHalfFovY);
  }
  // The corners' fit with the margin, or the bounding sphere's where nearer.
  EXPECT_LE(tallest, 1.0);
  EXPECT_GE(tallest, 1.0 - kFrameMargin - 1e-9);
  EXPECT_LT(widest, tallest);
  // The depth cue's range spans the box along the view axis.
  EXPECT_NEAR(c.depthFar - c.depthNear, 200.0, 1e-9);
}

TEST(RenderCamera, AzimuthElevationAndDistance) {
  const Camera c = parseCamera("azimuth=90, elevation=30,distance=2,fov=20", kLo, kHi, 320, 240);
  const Eigen::Vector3d v = c.eye - c.target;
  EXPECT_NEAR(v.norm(), 2.0 * (kHi - kLo).norm(), 1e-6);
  EXPECT_GT(v[0], 0.0);  // azimuth 90: the camera sits on +x and looks along -x
  EXPECT_NEAR(v[1], 0.0, 1e-6);
  EXPECT_NEAR(std::asin(v[2] / v.norm()), 30.0 * M_PI / 180.0, 1e-9);
  EXPECT_DOUBLE_EQ(c.fovYDegrees, 20.0);
  const Camera mm = parseCamera("distance=1234.5mm", kLo, kHi, 320, 240);
  EXPECT_NEAR((mm.eye - mm.target).norm(), 1234.5, 1e-9);
}

TEST(RenderCamera, ExplicitEyeTargetUp) {
  const Camera c = parseCamera("eye=1,2,3,target=4,5,6,up=0,1,0", kLo, kHi, 100, 50);
  EXPECT_TRUE(c.eye.isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(c.target.isApprox(Eigen::Vector3d(4, 5, 6)));
  EXPECT_TRUE(c.up.isApprox(Eigen::Vector3d(0, 1, 0)));
  EXPECT_EQ(c.width, 100);
  EXPECT_EQ(c.height, 50);
}

TEST(RenderCamera, RaysFormAnOrthonormalBasisAndAreSymmetric) {
  const CameraRays r = cameraRays(parseCamera("azimuth=33,elevation=-12", kLo, kHi, 64, 48));
  EXPECT_NEAR(r.forward.norm(), 1.0, 1e-12);
  EXPECT_NEAR(r.right.dot(r.forward), 0.0, 1e-12);
  EXPECT_NEAR(r.up.dot(r.forward), 0.0, 1e-12);
  EXPECT_NEAR(r.up.dot(r.right), 0.0, 1e-12);
  EXPECT_GT(r.up[2], 0.0);  // z up, row 0 at the top
  const Eigen::Vector3d a = r.direction(0, 0), b = r.direction(63, 47);
  EXPECT_TRUE((a + b).isApprox(2.0 * r.forward));
  EXPECT_NEAR(r.sy(0), r.tanHalfFovY * (1.0 - 1.0 / 48.0), 1e-12);
}

TEST(RenderCamera, MalformedDescriptionsAreInputErrors) {
  for (const char* bad : {"azimuth", "azimuth=x", "azimuth=1,azimuth=2", "zoom=2", "fov=0", "fov=180", "elevation=90",
                          "eye=1,2,3,azimuth=3", "eye=1,2", "eye=0,0,0,target=0,0,0", "eye=0,0,5,target=0,0,0,up=0,0,1",
                          "distance=-1", "azimuth=1e999"}) {
    EXPECT_THROW(parseCamera(bad, kLo, kHi, 64, 48), InputError) << bad;
  }
  try {
    parseCamera("zoom=2", kLo, kHi, 64, 48);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--camera: ", 0), 0u) << e.what();
  }
}

TEST(RenderCamera, ImageSize) {
  int w = 0, h = 0;
  parseImageSize("640x480", w, h);
  EXPECT_EQ(w, 640);
  EXPECT_EQ(h, 480);
  for (const char* bad : {"640", "x480", "640x", "0x10", "10x-1", "640x480x3", "abcxdef", "20000x10"})
    EXPECT_THROW(parseImageSize(bad, w, h), InputError) << bad;
}

TEST(RenderCuttingPlanes, AxisAndFreePlanes) {
  CuttingPlanes cuts;
  cuts.add("x>120mm");
  cuts.add("z<-40");
  cuts.add("plane=0,2,0,10");
  EXPECT_EQ(cuts.active().size(), 3u);
  EXPECT_TRUE(cuts.removes({121, 0, 0}));
  EXPECT_FALSE(cuts.removes({119, 0, 0}));
  EXPECT_TRUE(cuts.removes({0, 0, -41}));
  EXPECT_FALSE(cuts.removes({0, 0, -39}));
  EXPECT_TRUE(cuts.removes({0, 5.5, 0}));  // 2 * 5.5 > 10
  EXPECT_FALSE(cuts.removes({0, 4.5, 0}));
  // The plane itself is kept.
  EXPECT_FALSE(cuts.removes({120, 0, 0}));
}

TEST(RenderCuttingPlanes, MalformedPlanesAreInputErrors) {
  for (const char* bad : {"x", "x>", "w>3", "x=3", "x>3cm", "plane=1,0,0", "plane=0,0,0,1", "plane=a,b,c,d", "y<1e999"}) {
    CuttingPlanes cuts;
    EXPECT_THROW(cuts.add(bad), InputError) << bad;
  }
  CuttingPlanes cuts;
  cuts.add("x>1");
  EXPECT_THROW(cuts.add("x<5"), InputError);
  cuts.add("plane=1,1,0,0");
  EXPECT_THROW(cuts.add("plane=1,0,1,0"), InputError);
}

TEST(RenderPalette, DefaultColoursAndVisibility) {
  const Palette p(300);
  EXPECT_EQ(p.size(), 301u);
  EXPECT_FALSE(p.visible(0));
  for (Label l = 1; l <= 300; ++l) {
    EXPECT_TRUE(p.visible(l));
    EXPECT_FALSE(p.color(l) == p.color(Label(l - 1))) << l;
  }
  EXPECT_TRUE(Palette(300).color(123) == p.color(123));  // the same in every run
}

TEST(RenderPalette, OrganNamesPickColoursAndHideLabels) {
  const OrganTable organs = OrganTable::read(test::assetPath("icrp110_am_organs.dat"));
  Palette p = Palette::fromOrgans(organs, 141);
  const std::vector<int> skin = organs.idsMatching({"skin"});
  ASSERT_FALSE(skin.empty());
  for (int id : skin) {
    const Rgb c = p.color(Label(id));
    EXPECT_GT(c.r, c.b) << "skin is warm";
    EXPECT_GT(c.r, 150);
  }
  const std::vector<int> lungs = organs.idsMatching({"lung"});
  ASSERT_FALSE(lungs.empty());
  EXPECT_FALSE(p.color(Label(lungs[0])) == defaultLabelColor(Label(lungs[0])));

  p.hide("skin,3-5,7", &organs);
  for (int id : skin) EXPECT_FALSE(p.visible(Label(id)));
  for (Label l : {3, 4, 5, 7}) EXPECT_FALSE(p.visible(l));
  EXPECT_TRUE(p.visible(6));
  EXPECT_TRUE(p.visible(8));
}

TEST(RenderPalette, MalformedHideListsAreInputErrors) {
  const OrganTable organs = OrganTable::read(test::assetPath("icrp110_am_organs.dat"));
  for (const char* bad : {"", "1,,2", "5-3", "200", "1-200", "skin", "-3", "4x"}) {
    Palette p(141);
    EXPECT_THROW(p.hide(bad), InputError) << bad;
  }
  Palette p(141);
  EXPECT_THROW(p.hide("no such organ", &organs), InputError);
}

}  // namespace
}  // namespace vox
