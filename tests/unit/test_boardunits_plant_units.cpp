// Plant units: every spelling a file or a user gives, the canonical text, the conversion factor.
#include "boardunits/plant_units.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace mcg::boardunits {
namespace {

TEST(PlantUnits, SpellingsOfOneUnitParseAlike) {
  const PlantUnits rpm_per_v{false, PlantInput::v, PlantOutput::rpm};
  for (const char* text :
       {"v -> rpm", "V->rpm", "rpm/V", "rpm per V", "v -> rpm_true", "v -> rpm_measured"}) {
    ASSERT_TRUE(parse_plant_units(text).has_value()) << text;
    EXPECT_EQ(*parse_plant_units(text), rpm_per_v) << text;
  }
  const PlantUnits omega_per_v{};
  for (const char* text : {"v -> omega", "omega/v", "rad/s/V", "rad/s per V"}) {
    ASSERT_TRUE(parse_plant_units(text).has_value()) << text;
    EXPECT_EQ(*parse_plant_units(text), omega_per_v) << text;
  }
  EXPECT_EQ(*parse_plant_units("duty -> rpm"), (PlantUnits{false, PlantInput::duty, PlantOutput::rpm}));
  EXPECT_EQ(*parse_plant_units("rpm/duty"), (PlantUnits{false, PlantInput::duty, PlantOutput::rpm}));
  EXPECT_TRUE(parse_plant_units("loop")->loop);
}

TEST(PlantUnits, UnknownUnitsAreNotGuessed) {
  for (const char* text : {"", "v -> i", "i -> rpm", "rpm", "counts/duty", "V/rpm", "->", "rpm_cmd -> rpm"}) {
    EXPECT_FALSE(parse_plant_units(text).has_value()) << text;
  }
}

TEST(PlantUnits, CanonicalTextRoundTrips) {
  for (const char* text : {"v -> omega", "v -> rpm", "duty -> omega", "duty -> rpm", "loop"}) {
    EXPECT_EQ(units_text(*parse_plant_units(text)), text);
  }
  EXPECT_EQ(units_words(*parse_plant_units("rpm/V")), "rpm per V");
}

// rpm per V -> rad/s per V is 2 pi/60; duty 1 is the chain's 5 V x 4 = 20 V.
TEST(PlantUnits, FactorsToRadPerSecondPerVolt) {
  const LoopChain chain;
  EXPECT_DOUBLE_EQ(omega_per_v_factor(*parse_plant_units("v -> omega"), chain), 1.0);
  EXPECT_DOUBLE_EQ(omega_per_v_factor(*parse_plant_units("v -> rpm"), chain), 2.0 * std::numbers::pi / 60.0);
  EXPECT_DOUBLE_EQ(omega_per_v_factor(*parse_plant_units("duty -> omega"), chain), 1.0 / 20.0);
  EXPECT_DOUBLE_EQ(omega_per_v_factor(*parse_plant_units("duty -> rpm"), chain),
                   2.0 * std::numbers::pi / 60.0 / 20.0);
  LoopChain other;
  other.hbridge_gain = 2.4;
  EXPECT_DOUBLE_EQ(omega_per_v_factor(*parse_plant_units("duty -> omega"), other), 1.0 / 12.0);
}

}  // namespace
}  // namespace mcg::boardunits
