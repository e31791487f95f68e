// libFuzzer target: the record/replay log reader (runtime/loop/log.hpp) on any bytes: it returns
// a log or an error naming the offset and the field, never reads out of bounds; a log it accepts
// formats back without trouble; read as a recording cut short, a log without its end says where
// it ends. The snapshot a rotated log's later files begin with is the loop's state
// (loop::LoadState): the same bytes, and a parsed log's snapshot, are put back into the AUV's loop
// with a policy, which takes them or refuses them naming the field ("snapshot: ..."), never
// reading past them or taking a value its type cannot hold.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <span>
#include <string>

#include "runtime/loop/log.hpp"
#include "runtime/loop/policy_source.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace {

using namespace pbppo;

struct Auv {
  robot::RobotModel model;
  std::unique_ptr<policy::PolicyModel> policy;
  std::unique_ptr<loop::PolicySource> source;
};

Auv& TheAuv() {
  static Auv* auv = [] {
    auto* a = new Auv();
    auto m = robot::LoadRobotModel(std::string(PBPPO_SOURCE_DIR) + "/models/auv/robot.yaml");
    if (!m) std::abort();
    a->model = std::move(*m);
    policy::PolicySpec spec = policy::MakeRandomSpec({a->model.io->observation_size(), 16, a->model.io->action_size()},
                                                     policy::Activation::kTanh, 1);
    robot::ApplyLayoutToSpec(*a->model.io, spec);
    auto p = policy::PolicyModel::FromSpec(spec);
    if (!p) std::abort();
    a->policy = std::make_unique<policy::PolicyModel>(std::move(*p));
    auto s = loop::PolicySource::Create(a->model, *a->policy);
    if (!s) std::abort();
    a->source = std::move(*s);
    return a;
  }();
  return *auv;
}

void Restore(std::span<const std::uint8_t> bytes) {
  Auv& a = TheAuv();
  robot::RobotData data = robot::MakeRobotData(a.model);
  auto l = loop::MakeLoopData(a.model, a.source.get());
  const Status st = loop::LoadState(a.model, data, *l, bytes);
  if (!st && st.error().message.rfind("snapshot: ", 0) != 0) std::abort();
  if (st && (data.fields.size() != a.model.fields.size() || l->phase() > loop::Phase::kFailed)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Restore({data, size});
  // Read as a recording cut short may be: the same, or a log that says where it ends.
  auto cut =
      pbppo::loop::ParseLog(std::span<const std::uint8_t>(data, size), "fuzz.log", pbppo::loop::LogTail::kAcceptCut);
  if (!cut) {
    if (cut.error().message.rfind("fuzz.log: offset ", 0) != 0) std::abort();
  } else if (!cut->complete && (cut->cut_reason.empty() || cut->cut_at > size)) {
    std::abort();
  }
  auto log = pbppo::loop::ParseLog(std::span<const std::uint8_t>(data, size), "fuzz.log");
  if (!log) {
    if (log.error().message.rfind("fuzz.log: offset ", 0) != 0) std::abort();
    return 0;
  }
  if (!log->complete) std::abort();
  if (!log->snapshot.empty()) Restore(log->snapshot);
  for (const auto& r : log->records) {
    if (r.type == 2 && r.outputs.commands.size() != log->header.commands) std::abort();
    if (r.type == 1 && r.inputs.links.size() > log->header.links) std::abort();
  }
  return 0;
}
