// The ONNX importer on models built here: what it recognises acts as the graph (the runtime
// engine's Forward against the graph's float64 evaluation), and what it cannot run exactly is
// refused naming the node and its operator; the mapping file's errors name the field.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "policies/onnx/onnx_eval.hpp"
#include "policies/onnx/onnx_import.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "tests/policies/onnx/onnx_builder.hpp"

using namespace pbppo;
namespace ox = pbppo::onnx;
using test::OnnxBuilder;

namespace {

const char* kLayout = R"(
robot: testbot
observations:
  - {name: o0, unit: "1"}
  - {name: o1, unit: "1", scale: 2}
  - {name: o2, unit: "1"}
  - {name: o3, unit: "1"}
  - {name: o4, unit: "1"}
  - {name: o5, unit: "1"}
actions:
  - {name: a0, command: c0, unit: "1", scale: 0.5, offset: 0.1, low: -1, high: 1}
  - {name: a1, command: c1, unit: "1", scale: 0.5, offset: 0.1, low: -1, high: 1}
  - {name: a2, command: c2, unit: "1", scale: 2, offset: 0, low: -3, high: 3}
)";

robot::IoLayout Layout() {
  auto l = robot::ParseIoLayout(kLayout, "testbot.yaml");
  REQUIRE_MESSAGE(l.ok(), l.error().message);
  return *l;
}

std::string MapText(int inputs = 6, const std::string& obs = "[o0, o1, o2, o3, o4, o5]",
                    const std::string& act = "[a0, a1, a2]", int outputs = 3) {
  return "robot: testbot\ninput: {name: obs, size: " + std::to_string(inputs) +
         "}\noutput: {name: actions, size: " + std::to_string(outputs) + "}\nobservations: " + obs +
         "\nactions: " + act + "\n";
}

Result<ox::Imported> ImportBytes(const std::string& bytes, const std::string& map_text = MapText()) {
  const robot::IoLayout layout = Layout();
  auto model = ox::ParseModel({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, "m.onnx");
  if (!model) return std::move(model).error();
  auto map = ox::ParseMapping(map_text, "map.yaml", layout);
  if (!map) return std::move(map).error();
  return ox::Import(*model, *map, layout, {.source_name = "m.onnx", .source_sha256 = "00", .importer = "test"});
}

std::string ErrorOf(const std::string& bytes, const std::string& map_text = MapText()) {
  auto r = ImportBytes(bytes, map_text);
  return r.ok() ? std::string("(imported)") : r.error().message;
}

// The runtime engine on the imported blob against the graph evaluated in float64, on random
// observations: max |difference| / tolerance.
double EngineAgainstGraph(const std::string& bytes, const std::string& map_text = MapText()) {
  const robot::IoLayout layout = Layout();
  auto model = ox::ParseModel({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, "m.onnx");
  REQUIRE(model.ok());
  auto map = ox::ParseMapping(map_text, "map.yaml", layout);
  REQUIRE_MESSAGE(map.ok(), map.error().message);
  auto imp = ox::Import(*model, *map, layout, {});
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  auto blob = policy::EncodeBlob(imp->spec);
  REQUIRE(blob.ok());
  auto pm = policy::PolicyModel::FromBlob(*blob);
  REQUIRE_MESSAGE(pm.ok(), pm.error().message);
  auto pd = policy::MakePolicyData(*pm);
  REQUIRE(pd.ok());
  std::mt19937 rng(3);
  std::normal_distribution<float> nd(0.0f, 2.0f);
  double worst = 0;
  for (int r = 0; r < 200; ++r) {
    std::vector<float> obs(layout.observation_size());
    for (float& x : obs) x = nd(rng);
    std::copy(obs.begin(), obs.end(), pd->observation().begin());
    REQUIRE(policy::Forward(*pm, *pd) == policy::ForwardStatus::kOk);
    auto y = ox::Evaluate(*model, ox::InputRow(*map, obs));
    REQUIRE(y.ok());
    const auto cmd = ox::CommandsOf(*map, layout, *y);
    const auto ref = policy::ReferenceForward(imp->spec, obs.data());
    for (std::size_t k = 0; k < cmd.size(); ++k) {
      const double d = std::fabs(static_cast<double>(pd->action()[k]) - cmd[k]);
      worst = std::max(worst, d / ox::CheckTolerance(ref.error_bound[k], cmd[k]));
    }
  }
  return worst;
}

}  // namespace

TEST_CASE("Gemm chains with each activation run on the engine as the graph does") {
  for (const char* act : {"Elu", "Relu", "Tanh", "LeakyRelu"}) {
    CAPTURE(act);
    OnnxBuilder b(6);
    b.Gemm(16);
    auto* a = b.Node(act, {"$"});
    if (std::string(act) == "LeakyRelu") OnnxBuilder::Attr(a, "alpha", 0.2f);
    b.Gemm(16);
    b.Node(act, {"$"});
    b.Gemm(3);
    const std::string bytes = b.Bytes();
    auto imp = ImportBytes(bytes);
    REQUIRE_MESSAGE(imp.ok(), imp.error().message);
    CHECK(imp->spec.layers.size() == 3);
    CHECK(imp->spec.layers[2].activation == policy::Activation::kIdentity);
    CHECK(imp->check_max_ratio <= 1.0);
    CHECK(EngineAgainstGraph(bytes) <= 1.0);
  }
}

TEST_CASE("the mapping reorders inputs and outputs, and constant inputs fold into the first bias") {
  OnnxBuilder b(8);
  b.Gemm(12);
  b.Node("Elu", {"$"});
  b.Gemm(3);
  const std::string bytes = b.Bytes();
  const std::string map = MapText(8, "[o3, {constant: 0.7}, o0, o5, o1, {constant: -2}, o2, o4]", "[a2, a0, a1]");
  auto imp = ImportBytes(bytes, map);
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  CHECK(imp->spec.input_size == 6);
  CHECK(imp->spec.layers[0].in == 6);
  CHECK(EngineAgainstGraph(bytes, map) <= 1.0);
}

TEST_CASE(
    "a Sub/Div/Clip normaliser becomes the blob's, a Mul/Add one folds, a negative scale folds into the weights") {
  OnnxBuilder b(6);
  b.Elementwise("Sub", {0.5f, -1.0f, 2.0f, 0.0f, 3.0f, -0.25f});
  b.Elementwise("Div", {2.0f, 0.5f, 1.0f, 4.0f, 1.5f, 1.0f});
  b.Clip(-5.0f, 5.0f);
  b.Gemm(8);
  b.Node("Tanh", {"$"});
  b.Gemm(3);
  std::string bytes = b.Bytes();
  auto imp = ImportBytes(bytes);
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  CHECK(imp->spec.obs_clip == 5.0f);
  CHECK(imp->spec.obs_mean[2] == doctest::Approx(2.0));
  CHECK(imp->spec.obs_inv_std[1] == doctest::Approx(2.0));
  CHECK(EngineAgainstGraph(bytes) <= 1.0);

  OnnxBuilder c(6);  // a folded affine, one element negated, no clip
  c.Elementwise("Mul", {1.0f, -2.0f, 0.5f, 1.0f, 3.0f, 1.0f});
  c.Elementwise("Add", {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}, false);
  c.MatMulAdd(8);
  c.Node("Relu", {"$"});
  c.MatMulAdd(3);
  bytes = c.Bytes();
  imp = ImportBytes(bytes);
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  CHECK(imp->spec.obs_inv_std[1] == 1.0f);  // folded: the normaliser is the identity
  CHECK(EngineAgainstGraph(bytes) <= 1.0);

  OnnxBuilder d(6);  // the same with a clip after it: no exact blob normaliser exists
  d.Elementwise("Mul", {1.0f, -2.0f, 0.5f, 1.0f, 3.0f, 1.0f});
  d.Clip(-3.0f, 3.0f)->set_name("norm.clip");
  d.Gemm(3);
  CHECK(ErrorOf(d.Bytes()) ==
        "m.onnx: node 'norm.clip' (Clip): input element 1 is scaled by -2 before this clip: the blob's normaliser "
        "needs a positive scale");
}

TEST_CASE("an output Tanh, scale, offset and clip compose with the layout's action map") {
  OnnxBuilder b(6);
  b.Gemm(8);
  b.Node("Elu", {"$"});
  b.Gemm(3);
  b.Node("Tanh", {"$"});
  b.Elementwise("Mul", {2.0f, -1.0f, 0.5f});
  b.Elementwise("Add", {0.5f, 0.0f, -0.25f});
  b.Clip(-1.0f, 1.5f);
  const std::string bytes = b.Bytes();
  auto imp = ImportBytes(bytes);
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  const auto& s = imp->spec;
  CHECK(s.layers.back().activation == policy::Activation::kTanh);
  CHECK(s.action_scale[0] == doctest::Approx(0.5 * 2.0));
  CHECK(s.action_offset[0] == doctest::Approx(0.5 * 0.5 + 0.1));
  CHECK(s.action_low[0] == doctest::Approx(0.5 * -1.0 + 0.1));  // the model's clip, inside the layout's
  CHECK(s.action_high[0] == doctest::Approx(0.5 * 1.5 + 0.1));
  CHECK(s.action_low[2] == doctest::Approx(-2.0));  // 2 * the clip's [-1, 1.5] (tanh's range is no bound)
  CHECK(s.action_high[2] == doctest::Approx(3.0));
  CHECK(EngineAgainstGraph(bytes) <= 1.0);
}

TEST_CASE("Identity, Flatten, Constant nodes and opset-9 Clip attributes pass through") {
  OnnxBuilder b(6, 9);
  b.Node("Flatten", {"$"});
  b.Gemm(8);
  b.Node("Identity", {"$"});
  b.Node("Relu", {"$"});
  auto* k = b.graph().add_node();  // a Constant node as the last layer's bias source
  k->set_op_type("Constant");
  k->add_output("bias_const");
  auto* t = k->add_attribute();
  t->set_name("value");
  t->set_type(::onnx::AttributeProto::TENSOR);
  t->mutable_t()->set_data_type(::onnx::TensorProto::FLOAT);
  t->mutable_t()->add_dims(3);
  for (float v : {0.1f, 0.2f, 0.3f}) t->mutable_t()->add_float_data(v);
  b.Const("W_last", {3, 8}, b.Random(24, 0.5f));
  auto* g = b.Node("Gemm", {"$", "W_last", "bias_const"});
  OnnxBuilder::AttrInt(g, "transB", 1);
  b.set_width(3);
  auto* c = b.Node("Clip", {"$"});
  OnnxBuilder::Attr(c, "min", -2.0f);
  OnnxBuilder::Attr(c, "max", 2.0f);
  // The Constant node must come before its user: move it to the front.
  auto* nodes = b.graph().mutable_node();
  for (int i = nodes->size() - 1; i > 0; --i)
    if ((*nodes)[i].op_type() == "Constant") nodes->SwapElements(i, i - 1);
  const std::string bytes = b.Bytes();
  auto imp = ImportBytes(bytes);
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  CHECK(imp->spec.layers.size() == 2);
  CHECK(EngineAgainstGraph(bytes) <= 1.0);
}

TEST_CASE("what the engine cannot run exactly is refused, naming the node and its operator") {
  struct Case {
    const char* what;
    std::string (*make)();
    const char* error;
  };
  const Case cases[] = {
      {"softmax",
       [] {
         OnnxBuilder b(6);
         b.Gemm(3);
         b.Node("Softmax", {"$"}, "pi");
         return b.Bytes();
       },
       "node 'pi' (Softmax): operator not supported by the engine"},
      {"lstm",
       [] {
         OnnxBuilder b(6);
         b.Gemm(3);
         b.Node("LSTM", {"$"}, "mem");
         return b.Bytes();
       },
       "node 'mem' (LSTM): X has rank 2: an exported single step is [1, batch, features]"},
      {"elu alpha",
       [] {
         OnnxBuilder b(6);
         b.Gemm(4);
         OnnxBuilder::Attr(b.Node("Elu", {"$"}, "e"), "alpha", 0.5f);
         b.Gemm(3);
         return b.Bytes();
       },
       "node 'e' (Elu): alpha 0.5: the engine's ELU has alpha 1"},
      {"leaky alpha",
       [] {
         OnnxBuilder b(6);
         b.Gemm(4);
         OnnxBuilder::Attr(b.Node("LeakyRelu", {"$"}, "l"), "alpha", 2.f);
         b.Gemm(3);
         return b.Bytes();
       },
       "node 'l' (LeakyRelu): alpha 2 outside [0, 1]"},
      {"float16",
       [] {
         OnnxBuilder b(6);
         b.Gemm(3, "g");
         b.graph().mutable_initializer(0)->set_data_type(10);
         b.graph().mutable_initializer(0)->clear_float_data();
         return b.Bytes();
       },
       "node 'g' (Gemm): constant 'W0' is float16: the engine runs float32 weights only"},
      {"transA",
       [] {
         OnnxBuilder b(6);
         OnnxBuilder::AttrInt(b.Gemm(3, "g"), "transA", 1);
         return b.Bytes();
       },
       "node 'g' (Gemm): transA 1"},
      {"two activations",
       [] {
         OnnxBuilder b(6);
         b.Gemm(4);
         b.Node("Relu", {"$"});
         b.Node("Tanh", {"$"}, "t");
         b.Gemm(3);
         return b.Bytes();
       },
       "node 't' (Tanh): an activation after"},
      {"clip between layers",
       [] {
         OnnxBuilder b(6);
         b.Gemm(4);
         b.Node("Relu", {"$"});
         b.Clip(0, 6);
         b.Gemm(3, "g2");
         return b.Bytes();
       },
       "node 'g2' (Gemm): follows the output map"},
      {"activation first",
       [] {
         OnnxBuilder b(6);
         b.Node("Tanh", {"$"}, "t0");
         b.Gemm(3);
         return b.Bytes();
       },
       "node 't0' (Tanh): an activation before the first layer"},
      {"asymmetric clip",
       [] {
         OnnxBuilder b(6);
         b.Clip(-1, 2)->set_name("c");
         b.Gemm(3);
         return b.Bytes();
       },
       "node 'c' (Clip): bounds [-1, 2]: the blob's normaliser clips symmetrically"},
      {"division of a constant",
       [] {
         OnnxBuilder b(6);
         b.Elementwise("Div", {2.0f}, false)->set_name("d");
         b.Gemm(3);
         return b.Bytes();
       },
       "node 'd' (Div): divides a constant by the value"},
      {"shape mismatch",
       [] {
         OnnxBuilder b(6);
         b.Const("Wx", {3, 5}, std::vector<float>(15, 0.1f));
         OnnxBuilder::AttrInt(b.Node("Gemm", {"$", "Wx"}, "g"), "transB", 1);
         return b.Bytes();
       },
       "node 'g' (Gemm): weight 'Wx' [3, 5] (transposed) takes 5 inputs, the value before it has 6"},
      {"no layer",
       [] {
         OnnxBuilder b(6);
         b.Node("Relu", {"$"});
         return b.Bytes();
       },
       "an activation before the first layer"},
      {"other domain",
       [] {
         OnnxBuilder b(6);
         b.Gemm(3);
         b.Node("FusedGemm", {"$"}, "f")->set_domain("com.microsoft");
         return b.Bytes();
       },
       "node 'f' (FusedGemm): an operator of domain 'com.microsoft'"},
      {"branch",
       [] {
         OnnxBuilder b(6);
         b.Gemm(3);
         const std::string v = b.current();
         b.Node("Relu", {"$"});
         b.Node("Add", {"$", v}, "res");
         return b.Bytes();
       },
       "feeds 2 nodes"},
      {"output clip outside the layout",
       [] {
         OnnxBuilder b(6);
         b.Gemm(3);
         b.Clip(5, 6)->set_name("oc");
         return b.Bytes();
       },
       "node 'oc' (Clip): output element 0 ('a0') is held in [5, 6], commands [2.6, 3.1], outside the layout's "
       "limits [-1, 1]"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.what);
    const std::string e = ErrorOf(c.make());
    CHECK_MESSAGE(e.find(c.error) != std::string::npos, e);
  }
}

TEST_CASE("graph inputs and outputs the engine cannot take are refused, naming them") {
  {
    OnnxBuilder b(6);
    b.Gemm(3);
    OnnxBuilder::Port(b.graph().add_input(), "hidden", 4);
    CHECK(ErrorOf(b.Bytes()).find("2 graph inputs ('obs' used by node 'Gemm_0' (Gemm) input 0; 'hidden' used by no "
                                  "node)") != std::string::npos);
  }
  {
    OnnxBuilder b(6);
    b.Gemm(3);
    b.graph().mutable_input(0)->mutable_type()->mutable_tensor_type()->mutable_shape()->mutable_dim(1)->set_dim_param(
        "n");
    CHECK(ErrorOf(b.Bytes()) == "m.onnx: input 'obs' dimension 1 is symbolic ('n'): only the batch dimension may be");
  }
  {
    OnnxBuilder b(6);
    b.Gemm(3);
    b.graph().mutable_input(0)->mutable_type()->mutable_tensor_type()->mutable_shape()->mutable_dim(0)->set_dim_value(
        4);
    CHECK(ErrorOf(b.Bytes()) == "m.onnx: input 'obs' has a fixed batch of 4: the engine runs one row");
  }
  {
    OnnxBuilder b(6);
    b.Gemm(3);
    b.graph().mutable_input(0)->mutable_type()->mutable_tensor_type()->set_elem_type(::onnx::TensorProto::DOUBLE);
    CHECK(ErrorOf(b.Bytes()) == "m.onnx: input 'obs' is float64: the engine takes and gives float32");
  }
  {
    OnnxBuilder b(6);
    b.Gemm(3);
    const std::string bytes = b.Bytes();
    OnnxBuilder::Port(b.graph().add_output(), "value", 1);
    std::string two;
    b.model().SerializeToString(&two);
    CHECK(ErrorOf(two) == "m.onnx: 2 graph outputs ('actions', 'value'): the engine gives one action vector");
  }
}

TEST_CASE("the mapping file is checked against the layout and the model, naming the field") {
  OnnxBuilder b(6);
  b.Gemm(3);
  const std::string bytes = b.Bytes();
  const std::string all = "[o0, o1, o2, o3, o4, o5]";
  CHECK(ErrorOf(bytes, MapText(6, "[o0, o1, o2, o3, o4, oX]")) ==
        "map.yaml: observations[5]: 'oX' is not an observation of the 'testbot' layout");
  CHECK(ErrorOf(bytes, MapText(6, "[o0, o1, o2, o3, o4, o4]")) ==
        "map.yaml: observations[5]: 'o4' already feeds input element 4");
  CHECK(ErrorOf(bytes, MapText(6, "[o0, o1, o2, o3, o4, {constant: 1}]")) ==
        "map.yaml: observations: layout observation 'o5' feeds no input element (the policy would not see it)");
  CHECK(ErrorOf(bytes, MapText(7, all)) ==
        "map.yaml: observations: 6 entries, but input.size is 7 (one entry per input element)");
  CHECK(ErrorOf(bytes, MapText(6, all, "[a0, a1, a1]")) ==
        "map.yaml: actions[2]: 'a1' is already given by output element 1");
  CHECK(ErrorOf(bytes, MapText(6, all, "[a0, a1]", 2)) ==
        "map.yaml: actions: 2 entries, but the 'testbot' layout has 3 actions (each given by one output element)");
  CHECK(ErrorOf(bytes, "robot: otherbot\n") ==
        "map.yaml: robot: 'otherbot', but the robot's IO layout is for 'testbot'");
  CHECK(ErrorOf(bytes, MapText() + "gain: 2\n").find("gain") != std::string::npos);
  // Sizes stated in the mapping against the model.
  OnnxBuilder c(7);
  c.Gemm(3);
  CHECK(ErrorOf(c.Bytes(), MapText(6, all)) == "map.yaml: input: 'obs' of 6 elements, but m.onnx takes 'obs' of 7");
  // A recurrent model's state: pairs of names, each used once, never the observation or action.
  CHECK(ErrorOf(bytes, MapText() + "state: [h_in]\n") ==
        "map.yaml: state[0]: 'h_in' is not {input: NAME, output: NAME}");
  CHECK(ErrorOf(bytes, MapText() + "state: [{input: h, output: h2}, {input: h, output: h3}]\n") ==
        "map.yaml: state[1].input: 'h' is already a state input");
  CHECK(ErrorOf(bytes, MapText() + "state: [{input: a, output: h}, {input: b, output: h}]\n") ==
        "map.yaml: state[1].output: 'h' is already a state output");
  CHECK(ErrorOf(bytes, MapText() + "state: [{input: obs, output: h}]\n") ==
        "map.yaml: state[0].input: 'obs' is the observation input");
  CHECK(ErrorOf(bytes, MapText() + "state: [{input: h, output: actions}]\n") ==
        "map.yaml: state[0].output: 'actions' is the action output");
  CHECK(ErrorOf(bytes, MapText() + "state: [{input: h, output: h2, size: 3}]\n").find("size") != std::string::npos);
  // ... and against the model: a state the graph does not have.
  CHECK(ErrorOf(bytes, MapText() + "state: [{input: h_in, output: h_out}]\n") ==
        "map.yaml: state[0].input: 'h_in' is not a graph input of m.onnx");
}

TEST_CASE("truncated and corrupted models are refused or imported consistently, never crash") {
  OnnxBuilder b(6);
  b.Elementwise("Sub", {0.5f, -1.0f, 2.0f, 0.0f, 3.0f, -0.25f});
  b.Gemm(5);
  b.Node("Elu", {"$"});
  b.Gemm(3);
  const std::string bytes = b.Bytes();
  REQUIRE(ImportBytes(bytes).ok());
  int refused = 0, imported = 0;
  for (std::size_t n = 0; n < bytes.size(); ++n) {  // every truncation
    auto r = ImportBytes(bytes.substr(0, n));
    (r.ok() ? imported : refused) += 1;
    if (!r.ok()) CHECK_FALSE(r.error().message.empty());
  }
  CHECK(imported == 0);
  for (std::size_t i = 0; i < bytes.size(); ++i) {  // every byte flipped: refused, or it acts as its graph
    std::string c = bytes;
    c[i] = static_cast<char>(c[i] ^ 0x5a);
    auto r = ImportBytes(c);
    if (r.ok()) CHECK(r->check_max_ratio <= 1.0);
  }
  CHECK(refused == static_cast<int>(bytes.size()));
}

namespace {

// p, v0 and v1 keep 3 frames; c (last) none.
const char* kHistoryLayout = R"(
robot: histbot
observations:
  - {name: p, unit: "1", history: 3}
  - {name: v0, unit: "1", history: 3}
  - {name: v1, unit: "1", history: 3}
  - {name: c, unit: "1"}
actions:
  - {name: a0, command: c0, unit: "1", scale: 1, offset: 0, low: -1000, high: 1000}
  - {name: a1, command: c1, unit: "1", scale: 1, offset: 0, low: -1000, high: 1000}
)";

std::string HistoryMap(const std::string& history, const std::string& obs, int size) {
  return "robot: histbot\ninput: {name: obs, size: " + std::to_string(size) +
         "}\noutput: {name: actions, size: 2}\nhistory: " + history + "\nobservations: " + obs +
         "\nactions: [a0, a1]\n";
}

// The value a model input named like a layout input ("v0@-2") or a constant ("=0.5") holds at
// policy step t of the sequence the test feeds: p = 100 + t, v0 = 200 + t, v1 = 300 + t,
// c = 400 + t; k steps ago is step max(t - k, 0) (the first step fills every history slot).
double Expected(const std::string& input, int t) {
  if (input[0] == '=') return std::stod(input.substr(1));
  const auto at = input.find("@-");
  const std::string base = input.substr(0, at);
  const int lag = at == std::string::npos ? 0 : std::stoi(input.substr(at + 2));
  const double start = base == "p" ? 100 : base == "v0" ? 200 : base == "v1" ? 300 : 400;
  return start + std::max(t - lag, 0);
}

// Feeds the sequence through the layout's observation builder for 8 policy steps and checks every
// element of the model's input row against `expected` (what each element must be, written out).
// `with_c`: the layout with c (a frame-major stack cannot take it: c keeps no frames).
void CheckRows(const std::string& map_text, const std::vector<std::string>& expected, bool with_c = true) {
  std::string text = kHistoryLayout;
  if (!with_c) text.erase(text.find("  - {name: c"), text.find("actions:") - text.find("  - {name: c"));
  auto layout = robot::ParseIoLayout(text, "histbot.yaml");
  REQUIRE_MESSAGE(layout.ok(), layout.error().message);
  auto map = ox::ParseMapping(map_text, "map.yaml", *layout);
  REQUIRE_MESSAGE(map.ok(), map.error().message);
  auto builder = robot::ObservationBuilder::Create(*layout, {"p", "v0", "v1", "c"});  // c unread without it
  REQUIRE_MESSAGE(builder.ok(), builder.error().message);
  std::vector<float> obs(layout->observation_size());
  for (int t = 0; t < 8; ++t) {
    const double signals[] = {100.0 + t, 200.0 + t, 300.0 + t, 400.0 + t};
    builder->Build(signals, t == 0, obs.data());
    const std::vector<double> row = ox::InputRow(*map, obs);
    REQUIRE(row.size() == expected.size());
    for (std::size_t k = 0; k < row.size(); ++k) {
      CAPTURE(t);
      CAPTURE(k);
      CAPTURE(expected[k]);
      CHECK(row[k] == Expected(expected[k], t));
    }
  }
  // The model the mapping describes imports, and the engine acts as the graph on the stacked row.
  OnnxBuilder b(static_cast<int>(expected.size()));
  b.Gemm(8);
  b.Node("Elu", {"$"});
  b.Gemm(2);
  const std::string bytes = b.Bytes();
  auto model = ox::ParseModel({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, "m.onnx");
  REQUIRE(model.ok());
  auto imp = ox::Import(*model, *map, *layout, {});
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  CHECK(imp->check_max_ratio <= 1.0);
}

}  // namespace

TEST_CASE("stacked history in either order: every model input element is the layout's frame the mapping names") {
  // Frame-major, oldest frame first (a frame is every term at one step).
  CheckRows(HistoryMap("{length: 3, order: frame-major, oldest: first}", "[p, [v0, v1]]", 9),
            {"p@-2", "v0@-2", "v1@-2", "p@-1", "v0@-1", "v1@-1", "p", "v0", "v1"}, false);
  // Frame-major, newest first, a constant repeated in every frame.
  CheckRows(HistoryMap("{length: 3, order: frame-major, oldest: last}", "[v1, {constant: 0.5}, p, v0]", 12),
            {"v1", "=0.5", "p", "v0", "v1@-1", "=0.5", "p@-1", "v0@-1", "v1@-2", "=0.5", "p@-2", "v0@-2"}, false);
  // Term-major, oldest first (each term's frames together, a frame its components), and a term
  // of its own length.
  CheckRows(HistoryMap("{length: 3, order: term-major, oldest: first}", "[[v0, v1], p, {term: c, history: 1}]", 10),
            {"v0@-2", "v1@-2", "v0@-1", "v1@-1", "v0", "v1", "p@-2", "p@-1", "p", "c"});
  // Term-major, newest first.
  CheckRows(HistoryMap("{length: 3, order: term-major, oldest: last}", "[p, {term: c, history: 1}, [v0, v1]]", 10),
            {"p", "p@-1", "p@-2", "c", "v0", "v1", "v0@-1", "v1@-1", "v0@-2", "v1@-2"});
  // Without a history the mapping lists the layout's inputs themselves, as before.
  CheckRows(
      "robot: histbot\ninput: {name: obs, size: 10}\noutput: {name: actions, size: 2}\n"
      "observations: [c, p@-2, p@-1, p, [v0@-2, v1@-2], v0@-1, v1@-1, v0, v1]\nactions: [a0, a1]\n",
      {"c", "p@-2", "p@-1", "p", "v0@-2", "v1@-2", "v0@-1", "v1@-1", "v0", "v1"});
}

TEST_CASE("a stacked history the layout cannot give is refused, naming the field") {
  auto layout = robot::ParseIoLayout(kHistoryLayout, "histbot.yaml");
  REQUIRE(layout.ok());
  auto error = [&](const std::string& text) {
    auto m = ox::ParseMapping(text, "map.yaml", *layout);
    return m.ok() ? std::string("(parsed)") : m.error().message;
  };
  CHECK(error(HistoryMap("{length: 3, order: time-major, oldest: first}", "[p, v0, v1, c]", 12)) ==
        "map.yaml: history.order: 'time-major' is neither frame-major (every term of one frame, then the next "
        "frame) nor term-major (every frame of one term, then the next term)");
  CHECK(error(HistoryMap("{length: 3, order: frame-major, oldest: newest}", "[p, v0, v1, c]", 12)) ==
        "map.yaml: history.oldest: 'newest' is neither first nor last (where the oldest frame sits)");
  CHECK(error(HistoryMap("{length: 3, order: frame-major}", "[p, v0, v1, c]", 12)).find("history") !=
        std::string::npos);
  CHECK(error(HistoryMap("{length: 0, order: frame-major, oldest: last}", "[p, v0, v1]", 9)).find("history.length") !=
        std::string::npos);
  // c has no history in the layout: a frame-major stack would need c one step ago.
  CHECK(error(HistoryMap("{length: 3, order: frame-major, oldest: last}", "[p, v0, v1, c]", 12)) ==
        "map.yaml: observations[3]: 'c' has a history of 1 in the 'histbot' layout, but the mapping takes 3 frames "
        "of it (no 'c@-1')");
  CHECK(error(HistoryMap("{length: 3, order: frame-major, oldest: last}", "[p, v0, v1, {term: c, history: 1}]", 10)) ==
        "map.yaml: observations[3]: a term's own history needs the mapping's history with order term-major (a "
        "frame-major frame holds every term)");
  // The layout keeps 3 frames of p; a mapping of 2 leaves one unseen.
  CHECK(error(HistoryMap("{length: 2, order: term-major, oldest: first}", "[p, v0, v1, {term: c, history: 1}]", 7)) ==
        "map.yaml: observations: layout observation 'p@-2' feeds no input element (the policy would not see it)");
  CHECK(
      error(HistoryMap("{length: 3, order: term-major, oldest: first}", "[p, v0@-1, v1, {term: c, history: 1}]", 10)) ==
      "map.yaml: observations[1]: 'v0@-1': with a history the mapping names each term once (its frames follow "
      "from history)");
  CHECK(error(HistoryMap("{length: 3, order: term-major, oldest: first}", "[p, v0, v1, {term: c, history: 1}]", 12)) ==
        "map.yaml: observations: 10 input elements (every term's frames, history.length 3), but input.size is 12 (one "
        "entry per input element)");
  CHECK(error(HistoryMap("{length: 3, order: term-major, oldest: first}", "[p, [v0, vX], v1, {term: c, history: 1}]",
                         13)) == "map.yaml: observations[1][1]: 'vX' is not an observation of the 'histbot' layout");
  CHECK(error(HistoryMap("{length: 3, order: term-major, oldest: first}", "[p, [], v1, {term: c, history: 1}]", 10)) ==
        "map.yaml: observations[1]: an empty term");
}
