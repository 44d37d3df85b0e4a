// UnmodelledDraws: the draws of a version 2 trace the model does not blend, counted
// by blend mode from the draw state table (their fragments are in no record).
#include <gtest/gtest.h>

#include "traces/UnmodelledDraws.hpp"

namespace oit {
namespace {

DrawInfo draw(uint32_t id, BlendMode mode, uint64_t fragments) {
  DrawState s;
  s.blend = mode;
  s.fragments = fragments;
  return DrawInfo{id, mode == BlendMode::Off ? DrawClass::Opaque : DrawClass::Transparent, "d", s};
}

TEST(UnmodelledDraws, CountsEveryModeTheModelDoesNotBlend) {
  // Modelled: off 10, over 20, premultiplied over 30 fragments. Not: additive 7 + 4,
  // multiplicative 5, other 1 -> 4 draws, 17 fragments.
  const std::vector<DrawInfo> draws = {draw(0, BlendMode::Off, 10),           draw(1, BlendMode::Over, 20),
                                       draw(2, BlendMode::Additive, 7),       draw(3, BlendMode::PremultipliedOver, 30),
                                       draw(4, BlendMode::Multiplicative, 5), draw(5, BlendMode::Additive, 4),
                                       draw(6, BlendMode::Other, 1)};
  const UnmodelledDraws u = unmodelledDraws(draws);
  EXPECT_EQ(u.draws, 4u);
  EXPECT_EQ(u.fragments, 17u);
  EXPECT_EQ(u.draws_by_mode[static_cast<size_t>(BlendMode::Additive)], 2u);
  EXPECT_EQ(u.fragments_by_mode[static_cast<size_t>(BlendMode::Additive)], 11u);
  EXPECT_EQ(u.fragments_by_mode[static_cast<size_t>(BlendMode::Multiplicative)], 5u);
  EXPECT_EQ(u.fragments_by_mode[static_cast<size_t>(BlendMode::Other)], 1u);
  EXPECT_EQ(u.draws_by_mode[static_cast<size_t>(BlendMode::Over)], 0u);
  EXPECT_EQ(u.describe(),
            "4 draws, 17 fragments: additive 2 draws (11 fragments), multiplicative 1 draw (5 fragments), other 1 draw "
            "(1 fragment)");
}

TEST(UnmodelledDraws, NoneInVersionOneOrModelledDraws) {
  // Version 1 draws have no state: nothing is unmodelled.
  const std::vector<DrawInfo> v1 = {DrawInfo{0, DrawClass::Transparent, "a"}, DrawInfo{1, DrawClass::Opaque, "b"}};
  EXPECT_EQ(unmodelledDraws(v1).draws, 0u);
  const UnmodelledDraws u = unmodelledDraws({draw(0, BlendMode::Over, 3), draw(1, BlendMode::Off, 2)});
  EXPECT_EQ(u.draws, 0u);
  EXPECT_EQ(u.fragments, 0u);
  EXPECT_EQ(u.describe(), "0 draws, 0 fragments");
}

}  // namespace
}  // namespace oit
