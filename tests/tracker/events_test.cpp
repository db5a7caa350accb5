// The event stream's rules on their own (tracker/events.hpp), fed made-up traces at 500 Hz: a
// contact is made or broken once the change has held for kContactHold and is stamped with its
// first sample; gated measurements, dropped and rejected samples close to each other in time
// form one burst; the grip loosens once while it flickers; every health state change is one
// event; the words name the link and the figure.
#include <gtest/gtest.h>

#include <vector>

#include "inhand/tracker/events.hpp"

namespace inhand {
namespace {

constexpr double kDt = 0.002;

HandModel ThreeLinks() {
  HandModel hand;
  hand.links.resize(3);
  hand.links[0].name = "palm";
  hand.links[1].name = "index_tip";
  hand.links[2].name = "thumb_tip";
  return hand;
}

FilterTrace Touching(int link, ContactKind kind, bool gated = false, double mahalanobis = 0.0) {
  FilterTrace trace;
  FilterTrace::Contact c;
  c.link = link;
  c.kind = kind;
  c.distance = kind == ContactKind::kKinematic ? -0.002 : 0.001;
  c.force_P = Vec3(0.0, 3.0, 4.0);
  c.gated = gated;
  c.mahalanobis = mahalanobis;
  trace.contacts.push_back(c);
  return trace;
}

std::vector<TrackerEvent> Of(const std::vector<TrackerEvent>& events, EventKind kind) {
  std::vector<TrackerEvent> out;
  for (const TrackerEvent& e : events)
    if (e.kind == kind) out.push_back(e);
  return out;
}

TEST(EventDetector, AContactCountsOnceItHasHeldAndIsStampedWithItsFirstSample) {
  const HandModel hand = ThreeLinks();
  EventDetector d(hand, 0.25);
  std::vector<TrackerEvent> out;
  double t = 1.0;
  for (int i = 0; i < 10; ++i, t += kDt) d.OnSample(t, FilterTrace(), Health(), out);
  // A blip of 3 samples (6 ms) is no contact.
  for (int i = 0; i < 3; ++i, t += kDt)
    d.OnSample(t, Touching(1, ContactKind::kTorque), Health(), out);
  for (int i = 0; i < 40; ++i, t += kDt) d.OnSample(t, FilterTrace(), Health(), out);
  EXPECT_TRUE(out.empty());
  // Held: made at its first sample, found kContactHold later; a flicker of one sample inside
  // it does not break it.
  const double onset = t;
  for (int i = 0; i < 100; ++i, t += kDt)
    d.OnSample(t, i == 50 ? FilterTrace() : Touching(1, ContactKind::kTorque), Health(), out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].kind, EventKind::kContactMade);
  EXPECT_EQ(out[0].subject, 1);
  EXPECT_DOUBLE_EQ(out[0].t, onset);
  EXPECT_EQ(out[0].count, 1);           // torque-confirmed
  EXPECT_DOUBLE_EQ(out[0].value, 5.0);  // |(0, 3, 4)| N
  EXPECT_EQ(EventMessage(out[0], hand), "index_tip touches the object (torque-confirmed, 5.00 N)");
  const double left = t;
  for (int i = 0; i < 30; ++i, t += kDt) d.OnSample(t, FilterTrace(), Health(), out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].kind, EventKind::kContactBroken);
  EXPECT_DOUBLE_EQ(out[1].t, left);
  EXPECT_NEAR(out[1].duration, left - onset, 1e-12);
  // A kinematic contact: its depth.
  for (int i = 0; i < 30; ++i, t += kDt)
    d.OnSample(t, Touching(2, ContactKind::kKinematic), Health(), out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[2].count, 0);
  EXPECT_DOUBLE_EQ(out[2].value, 0.002);
  EXPECT_EQ(EventMessage(out[2], hand), "thumb_tip touches the object (kinematic, 2.00 mm deep)");
  // Candidates and gated contacts are not contacts.
  out.clear();
  d.Reset();
  for (int i = 0; i < 50; ++i, t += kDt) {
    FilterTrace trace = Touching(1, ContactKind::kCandidate);
    trace.contacts.push_back(Touching(2, ContactKind::kTorque, true).contacts[0]);
    d.OnSample(t, trace, Health(), out);
  }
  EXPECT_TRUE(Of(out, EventKind::kContactMade).empty());
}

TEST(EventDetector, GatedMeasurementsAndDroppedSamplesComeInBursts) {
  const HandModel hand = ThreeLinks();
  EventDetector d(hand, 0.25);
  std::vector<TrackerEvent> out;
  double t = 0.0;
  // Two stretches of gated contacts 0.1 s apart (one burst), another 0.5 s later.
  const auto gated = [&](int samples, int link, double mahalanobis) {
    for (int i = 0; i < samples; ++i, t += kDt)
      d.OnSample(t, Touching(link, ContactKind::kTorque, true, mahalanobis), Health(), out);
  };
  const auto quiet = [&](double seconds) {
    for (const double end = t + seconds; t < end - 1e-9; t += kDt)
      d.OnSample(t, FilterTrace(), Health(), out);
  };
  const double first = t;
  gated(5, 2, 30.0);
  quiet(0.1);
  gated(10, 1, 50.0);
  const double second_end = t - kDt;
  quiet(0.5);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].kind, EventKind::kContactsGated);
  EXPECT_DOUBLE_EQ(out[0].t, first);
  EXPECT_EQ(out[0].count, 15);
  EXPECT_NEAR(out[0].duration, second_end - first, 1e-12);
  EXPECT_EQ(out[0].subject, 1);  // gated 10 times against 5
  EXPECT_DOUBLE_EQ(out[0].value, 50.0);
  const double third = t;
  gated(3, 2, 20.0);
  EXPECT_EQ(out.size(), 1u);  // still open
  d.Close(out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[1].t, third);
  EXPECT_EQ(out[1].count, 3);
  EXPECT_EQ(out[1].subject, 2);
  // Samples rejected: one burst naming the first one's joint; dropped ones another.
  out.clear();
  d.OnSampleRejected(t, 4, 3.5, out);
  d.OnSampleRejected(t + 0.01, 2, -1.0, out);
  d.OnSampleDropped(t + 0.01, out);
  d.OnSampleDropped(t + 0.02, out);
  quiet(0.3);
  ASSERT_EQ(out.size(), 2u);
  const TrackerEvent rejected = Of(out, EventKind::kSamplesRejected).at(0);
  EXPECT_EQ(rejected.count, 2);
  EXPECT_EQ(rejected.subject, 4);
  EXPECT_DOUBLE_EQ(rejected.value, 3.5);
  EXPECT_EQ(Of(out, EventKind::kSamplesDropped).at(0).count, 2);
  // Images whose gate refused most features: a burst of images.
  out.clear();
  EventDetector::Image image;
  ImageEvidence& im = image.evidence;
  im.offered = 20;
  for (int i = 0; i < 3; ++i) {
    im.t_capture = t + 0.1 * i;
    im.used = i == 1 ? 4 : 8;  // 80 %, then 60 % refused
    d.OnImage(image, out);
  }
  im.t_capture = t + 0.3, im.used = 15;  // 25 % refused: not part of it
  d.OnImage(image, out);
  d.Close(out);
  const std::vector<TrackerEvent> vision = Of(out, EventKind::kVisionGated);
  ASSERT_EQ(vision.size(), 1u);
  EXPECT_EQ(vision[0].count, 3);
  EXPECT_DOUBLE_EQ(vision[0].value, 0.8);
}

TEST(EventDetector, HealthChangesTheGripAndTheImagesEachSayOnce) {
  const HandModel hand = ThreeLinks();
  EventDetector d(hand, 0.25);
  std::vector<TrackerEvent> out;
  Health inconsistent;
  inconsistent.state = HealthState::kInconsistent;
  inconsistent.cause = HealthCause::kPressingInAir;
  inconsistent.subject = 2;
  inconsistent.value = 0.0231;
  inconsistent.since = 1.2;
  FilterTrace slipping;
  slipping.slipping = true;
  double t = 1.0;
  for (int i = 0; i < 200; ++i, t += kDt)
    d.OnSample(t, i % 7 == 0 ? slipping : FilterTrace(), i >= 100 ? inconsistent : Health(), out);
  const std::vector<TrackerEvent> grip = Of(out, EventKind::kGripLoosened);
  ASSERT_EQ(grip.size(), 1u);  // every 14 ms for 0.4 s: one loosening
  EXPECT_DOUBLE_EQ(grip[0].t, 1.0);
  const std::vector<TrackerEvent> health = Of(out, EventKind::kHealth);
  ASSERT_EQ(health.size(), 1u);
  EXPECT_NEAR(health[0].t, 1.2, 1e-9);
  EXPECT_EQ(EventSubject(health[0], hand), "inconsistent");
  EXPECT_EQ(EventMessage(health[0], hand),
            "inconsistent since 1.20 s: thumb_tip presses but the object is 23.1 mm from it");
  // Images: lost, then found 40 mm away by a relocalization; tags elsewhere once while they stay.
  out.clear();
  EventDetector::Image image;
  ImageEvidence& im = image.evidence;
  im.t_capture = 2.0, im.features_lost = true, im.tags_elsewhere = true;
  d.OnImage(image, out);
  im.t_capture = 2.1;
  d.OnImage(image, out);
  im.t_capture = 2.2, im.features_lost = false, im.relocalized = 0.04, im.tags_elsewhere = false;
  d.OnImage(image, out);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out[0].kind, EventKind::kFeaturesLost);
  EXPECT_EQ(out[1].kind, EventKind::kTagsElsewhere);
  EXPECT_EQ(out[2].kind, EventKind::kRelocalized);
  EXPECT_EQ(out[3].kind, EventKind::kFeaturesFound);
  EXPECT_DOUBLE_EQ(out[3].value, 0.04);
  EXPECT_EQ(EventMessage(out[3], hand),
            "the image features match again, the object 40.0 mm from the estimate");
  for (int k = 0; k < kNumEventKinds; ++k)
    EXPECT_STRNE(EventKindName(static_cast<EventKind>(k)), "?") << k;
}

}  // namespace
}  // namespace inhand
