// Clip schedules driven through worked sequences.
#include <doctest/doctest.h>

#include <cmath>

#include "runtime/core/random.hpp"

#include "policies/trainer/clip_schedule.hpp"

namespace pbppo::trainer {
namespace {

ScheduleConfig Config(const std::string& s, std::vector<double> arms) {
  auto c = ParseSchedule(s, arms);
  REQUIRE_MESSAGE(c.ok(), (c.ok() ? "" : c.error().message));
  return c.value();
}

TEST_CASE("arm sets: linspace and lists, values in [0, 1]") {
  auto a = ParseArms("0.05:0.4:6");
  REQUIRE(a.ok());
  REQUIRE(a->size() == 6);
  CHECK(a->front() == doctest::Approx(0.05));
  CHECK((*a)[1] == doctest::Approx(0.12));
  CHECK(a->back() == doctest::Approx(0.4));
  auto l = ParseArms("0.1,0.2,0.3");
  REQUIRE(l.ok());
  CHECK(l->size() == 3);
  auto one = ParseArms("0.2:0.2:1");
  REQUIRE(one.ok());
  CHECK(one->size() == 1);

  auto bad = ParseArms("0.1,1.2");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message == "--arms: clip bound 1.2 is outside [0, 1]");
  CHECK(ParseArms("-0.1:0.3:4").error().message.find("-0.1 is outside [0, 1]") != std::string::npos);
  CHECK(ParseArms("0.1:0.3").error().message.find("is not MIN:MAX:N") != std::string::npos);
  CHECK(ParseArms("0.1:0.3:x").error().message.find("count 'x'") != std::string::npos);
  CHECK(ParseArms("0.4:0.1:3").error().message.find("below min") != std::string::npos);
  CHECK(ParseArms("0.1,abc").error().message.find("'abc' is not a number") != std::string::npos);
}

TEST_CASE("schedule names, variants and defaults") {
  CHECK(Config("fixed:0.2", {}).arms == std::vector<double>{0.2});
  CHECK(ParseSchedule("fixed:1.5", {}).error().message.find("1.5 is outside [0, 1]") != std::string::npos);
  const auto p = Config("pbppo-paper:wo-ad", {0.1, 0.2});
  CHECK(p.mode == ScheduleMode::kPaper);
  CHECK_FALSE(p.advantage);
  CHECK(p.lambda == 5.0);
  CHECK(p.gamma == 0.99);
  CHECK(Config("pbppo-paper", {0.1}).advantage);            // the paper's wi-ad
  CHECK_FALSE(Config("pbppo-reference", {0.1}).advantage);  // the released script's default, wo-ad
  CHECK(Config("pbppo-reference:wi-ad", {0.1}).advantage);
  CHECK(Config("pbppo", {0.1}).mode == ScheduleMode::kDucb);
  CHECK(ParseSchedule("pbppo-paper:xx", {0.1}).error().message.find("variant 'xx'") != std::string::npos);
  CHECK(ParseSchedule("adaptive", {0.1}).error().message.find("'adaptive' unknown") != std::string::npos);
  CHECK(ParseSchedule("pbppo", {0.1, 2.0}).error().message.find("2 is outside [0, 1]") != std::string::npos);
}

TEST_CASE("fixed schedule always returns its bound") {
  auto s = MakeClipSchedule(Config("fixed:0.2", {}));
  for (int i = 0; i < 5; ++i) {
    CHECK(s->epsilon(s->Choose()) == 0.2);
    s->Update(0, 1.0, 0.0);
  }
  CHECK_FALSE(s->uses_feedback());
}

TEST_CASE("paper rule: worked sequence") {
  for (bool adv : {false, true}) {
    auto s = MakeClipSchedule(Config(adv ? "pbppo-paper:wi-ad" : "pbppo-paper:wo-ad", {0.1, 0.2, 0.3}));
    CHECK(s->Choose() == 0);  // N = 0: every bonus 0, every value 0, lowest index
    s->Update(0, 10, 0);
    CHECK(s->Choose() == 1);  // unpulled arms carry bonus 5 / sqrt(1e-6)
    s->Update(1, 20, 10);
    CHECK(s->Choose() == 2);
    s->Update(2, 30, 20);
    CHECK(s->Choose() == 2);  // equal bonuses, E = 10, 20, 30
    const double mean = adv ? 20.0 : 0.0;
    CHECK(s->arms()[2].value == doctest::Approx(30 - mean));
    CHECK(s->arms()[2].bonus == doctest::Approx(5 * std::sqrt(3 / (1 + 1e-6))));
    s->Update(2, 30, 30);
    // E2 = 0.99 * 30 + 30 = 59.7, N = 4, N2 = 2.
    CHECK(s->Choose() == 2);
    CHECK(s->arms()[2].value == doctest::Approx(59.7 - (adv ? (10 + 20 + 59.7) / 3 : 0.0)));
    CHECK(s->arms()[0].bonus == doctest::Approx(5 * std::sqrt(4 / (1 + 1e-6))));
    CHECK(s->arms()[2].count == 2);
  }
}

TEST_CASE("reference rule: index-order sweep at the start, near round-robin after") {
  auto s = MakeClipSchedule(Config("pbppo-reference:wo-ad", {0.02, 0.1, 0.2, 0.3, 0.4, 0.5}));
  std::vector<int> chosen;
  for (int i = 0; i < 12; ++i) {
    const int a = s->Choose();
    chosen.push_back(a);
    s->Update(a, 100.0 + 10.0 * a, 0);  // positive returns, larger for higher arms
  }
  for (int i = 0; i < 6; ++i) CHECK(chosen[static_cast<std::size_t>(i)] == i);
  // The exploitation term lies in (0, 1] beside a bonus >= 5: every arm gets a second pull
  // within the next six iterations.
  std::vector<int> counts(6, 0);
  for (int i = 6; i < 12; ++i) counts[static_cast<std::size_t>(chosen[static_cast<std::size_t>(i)])]++;
  for (int c : counts) CHECK(c == 1);
  for (const auto& a : s->arms()) {
    CHECK(a.value > 0.0);
    CHECK(a.value <= 1.0);
    CHECK(a.bonus >= 5.0);
  }
}

TEST_CASE("reference rule, wi-ad as the script computes it: the ratios shifted by their mean, the same choices") {
  auto wo = MakeClipSchedule(Config("pbppo-reference:wo-ad", {0.1, 0.2, 0.3}));
  auto wi = MakeClipSchedule(Config("pbppo-reference:wi-ad", {0.1, 0.2, 0.3}));
  const double returns[] = {50, -20, 80, 10, -5, 120, 30, 60, -40, 90, 15, 70};
  for (double r : returns) {
    const int a = wo->Choose();
    CHECK(wi->Choose() == a);
    double mean = 0;
    for (const auto& arm : wo->arms()) mean += arm.value;
    mean /= 3;
    for (std::size_t i = 0; i < 3; ++i) CHECK(wi->arms()[i].value == doctest::Approx(wo->arms()[i].value - mean));
    wo->Update(a, r, 0);
    wi->Update(a, r, 0);
  }
}

TEST_CASE("reference rule with negative returns: the ranking flips, a zero denominator does not crash") {
  auto s = MakeClipSchedule(Config("pbppo-reference:wo-ad", {0.1, 0.2}));
  CHECK(s->Choose() == 0);
  s->Update(0, -100, 0);
  CHECK(s->Choose() == 1);
  s->Update(1, -10, 0);
  s->Choose();
  // E = (-100, -10): denominator -9.999, so the worse arm gets the larger exploitation term.
  CHECK(s->arms()[0].value == doctest::Approx(-100 / -9.999));
  CHECK(s->arms()[1].value == doctest::Approx(-10 / -9.999));
  CHECK(s->arms()[0].value > s->arms()[1].value);

  auto z = MakeClipSchedule(Config("pbppo-reference:wo-ad", {0.1, 0.2}));
  z->Choose();
  z->Update(0, -0.001, 0);
  z->Choose();
  z->Update(1, -0.001, 0);
  const int a = z->Choose();  // max E + 0.001 == 0: exploitation 0 for every arm
  CHECK((a == 0 || a == 1));
  for (const auto& arm : z->arms()) {
    CHECK(arm.value == 0.0);
    CHECK(std::isfinite(arm.bonus));
  }
}

TEST_CASE("pbppo (discounted UCB): improvement rewards, running scale, discounted counts") {
  ScheduleConfig c = Config("pbppo", {0.1, 0.2, 0.3});
  auto s = MakeClipSchedule(c);
  CHECK(s->Choose() == 0);
  s->Update(0, 110, 100);  // delta 10, scale 10, x = 1
  CHECK(s->Choose() == 1);
  s->Update(1, 105, 110);  // delta -5, scale 0.95 * 10 + 0.05 * 5 = 9.75, x = -5 / 9.75
  CHECK(s->arms()[0].count == doctest::Approx(0.95));
  CHECK(s->Choose() == 2);  // never pulled goes first
  s->Update(2, 105, 105);   // delta 0: x = 0
  const int a = s->Choose();
  // counts: 0.9025, 0.95, 1; sums: 0.9025, -0.5128 * 0.95, 0
  const double n = 0.9025 + 0.95 + 1.0;
  CHECK(s->arms()[0].value == doctest::Approx(1.0));
  CHECK(s->arms()[1].value == doctest::Approx(-5.0 / 9.75));
  CHECK(s->arms()[0].bonus == doctest::Approx(std::sqrt(std::log(n) / 0.9025)));
  CHECK(a == 0);
}

TEST_CASE("pbppo finds the arm whose updates improve return, under noise") {
  auto s = MakeClipSchedule(Config("pbppo", {0.05, 0.1, 0.2, 0.3}));
  const double gain[4] = {-1.0, 2.0, 0.5, -3.0};
  Rng rng(1);
  double r = -1000;
  std::vector<int> count(4, 0);
  for (int i = 0; i < 300; ++i) {
    const int a = s->Choose();
    count[static_cast<std::size_t>(a)]++;
    const double next = r + gain[a] + rng.Normal();
    s->Update(a, next, r);
    r = next;
  }
  CHECK(count[1] > 150);
  CHECK(count[1] > count[0] + count[2] + count[3]);
}

}  // namespace
}  // namespace pbppo::trainer
