// The modality sets' names and colours: a parser test, kept apart from the end-to-end runs of
// player_test.cpp so that the sanitizer pass builds it without them.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "inhand/app/modalities.hpp"
#include "inhand/core/error.hpp"

namespace inhand {
namespace {

TEST(Modalities, EveryCombinationParsesToOneNameAndColour) {
  const std::vector<app::ModalitySet> sets = app::ParseModalities("j,jt,ja,jf,jat,jtf,jfa,jfat");
  const std::vector<std::string> names = {"j", "jt", "ja", "jf", "jta", "jtf", "jaf", "jtaf"};
  ASSERT_EQ(sets.size(), names.size());
  for (std::size_t i = 0; i < sets.size(); ++i) {
    EXPECT_EQ(sets[i].name, names[i]);
    EXPECT_EQ(sets[i].torque, names[i].find('t') != std::string::npos);
    EXPECT_EQ(sets[i].tags, names[i].find('a') != std::string::npos);
    EXPECT_EQ(sets[i].features, names[i].find('f') != std::string::npos);
    for (std::size_t k = 0; k < i; ++k) {
      const Rgb a = sets[i].colour, b = sets[k].colour;
      EXPECT_GT(std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b), 60)
          << names[i] << " vs " << names[k];
    }
  }
  // The paper's four keep the paper's colours.
  EXPECT_EQ(sets[1].colour.b, kColourTorques.b);
  EXPECT_EQ(sets[5].colour.g, kColourFeatures.g);
  for (const char* bad : {"", "t", "jx", "jtt", "j,ja,aj"})
    EXPECT_THROW(app::ParseModalities(bad), InputError) << bad;
  EXPECT_THROW(app::ParseModalities("ja,jaa"), InputError);
  EXPECT_THROW(app::ParseModalities("jta,jat"), InputError);  // the same set twice
  EXPECT_EQ(app::DefaultModalities(true, true, true), "j,jt,jta,jtf");
  EXPECT_EQ(app::DefaultModalities(false, true, true), "j,ja,jf");
  EXPECT_EQ(app::DefaultModalities(false, false, true), "j");
}

}  // namespace
}  // namespace inhand
