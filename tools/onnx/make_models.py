#!/usr/bin/python3
"""Writes the ONNX test models of `pbppo import-onnx` and their mapping files.

    tools/onnx/make_models.py OUT_DIR --flat-json F --auv-json A

F and A are `pbppo inspect --json --weights` of policies/frozen/quadruped_walk/flat.blob and
policies/frozen/auv_nav/auv_nav.blob. Everything is deterministic (fixed seeds): the same JSON
gives byte-identical files. Uses Debian's python3-onnx and python3-numpy only.

OUT_DIR/
  rsl_rl_walk.onnx + .yaml      flat.blob as an rsl_rl / legged_gym actor 48-512-256-128-12 ELU
                                (Gemm transB=1); the 3 base_lin_vel inputs are fed a constant 0
  normalised_walk.onnx + .yaml  flat.blob behind an EmpiricalNormalization-style normaliser
                                (Sub mean, Div std+eps, Clip +-100), inputs and outputs reordered
  sb3_auv.onnx + .yaml          auv_nav.blob as a stable-baselines3 actor 64-64 tanh (MatMul + Add),
                                its normaliser folded into Mul + Add + Clip, output Clip(-1, 1)
  leaky_tanh_head.onnx          6-16-16-3 LeakyReLU(0.2) on random weights, Tanh, Mul, Add at the
                                output: for importer unit tests with a synthetic layout
  history_frame_major.onnx + .yaml, history_term_major.onnx + .yaml
                                one linear layer over 4 stacked frames of the terms p and
                                (v0, v1), frame-major newest first (as rl_sar's HIMLoco stacks) and
                                term-major oldest first (as Isaac Lab's observation history
                                flattens); each output reads named frames: a0 = p(now) +
                                0.5 v1(3 steps ago), a1 = v0(1 step ago) - v1(2 steps ago)
  lstm_walk.onnx + .yaml        flat.blob's second layer run by an LSTM 64 (its cell input eps times the
                                layer's, gates held open, forget 0.018): walks as flat.blob, state h, c
  gru_actor.onnx + .yaml        GRU 32 (linear_before_reset 1, as torch) and a 16 ELU head, random weights
  gru_lbr0.onnx + .yaml         GRU 24 (linear_before_reset 0, ONNX's default) behind a Sub/Div
                                normaliser, a 16 tanh head
  lstm_stacked.onnx + .yaml     two stacked LSTM 24 layers as torch exports num_layers=2: the state
                                inputs [2, batch, 24] sliced per layer, the outputs concatenated
  unitree_walk.onnx + .deploy.yaml
                                flat.blob as unitree_rl_lab exports an Isaac Lab policy: joints breadth
                                first (joint_ids_map), two frames of base_ang_vel and projected_gravity;
                                unitree_walk.env.yaml: the same as Isaac Lab's params/env.yaml;
                                unitree_walk.agent.yaml: the run's rsl_rl params/agent.yaml
  bad/*.onnx, bad/README        models the importer must refuse, and what its error must name

The good models are what torch.onnx.export writes for these trainers (opset 17, producer
"pytorch", torch's node naming); ir_version is 8 so that ONNX Runtime 1.30 loads them.
"""
import argparse
import json
import os
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

OPSET = 17
IR_VERSION = 8
PRODUCER = "pytorch"
PRODUCER_VERSION = "2.1.0"

# rsl_rl's EmpiricalNormalization adds this to the running std before dividing.
NORMALIZER_EPS = 1e-2


# ------------------------------------------------------------------------------------------ helpers


def f32(a):
    return np.ascontiguousarray(np.asarray(a, dtype=np.float32))


def init(name, array):
    return numpy_helper.from_array(f32(array), name)


def scalar(name, value):
    return numpy_helper.from_array(np.array(value, dtype=np.float32), name)


def normaliser_nodes(first, second, clip):
    """The input normaliser as torch exports it: two elementwise ops with constants, then Clip(-clip, clip).
    first/second: (op, initializer name, values). Returns (nodes, initializers); the output is
    '/normalizer/Clip_output_0'."""
    nodes, inits, x = [], [], "obs"
    for op, name, values in (first, second):
        y = f"/normalizer/{op}_output_0"
        nodes.append(helper.make_node(op, [x, name], [y], name=f"/normalizer/{op}"))
        inits.append(init(name, values))
        x = y
    lo, hi = "/normalizer/Constant_output_0", "/normalizer/Constant_1_output_0"
    nodes.append(helper.make_node("Clip", [x, lo, hi], ["/normalizer/Clip_output_0"], name="/normalizer/Clip"))
    inits += [scalar(lo, -clip), scalar(hi, clip)]
    return nodes, inits


def torch_gemm_chain(layers, act="Elu", act_attrs=None):
    """An nn.Sequential of Linear and activation layers as torch exports it, from "obs" to "actions":
    Gemm (transB 1) at torch's indices 0, 2, 4, ..., the activation at 1, 3, 5, ...; layers: (W [out][in], b)."""
    nodes, inits, x = [], [], "obs"
    for k, (w, b) in enumerate(layers):
        wn, bn = f"actor.{2 * k}.weight", f"actor.{2 * k}.bias"
        inits += [init(wn, w), init(bn, b)]
        last = k == len(layers) - 1
        y = "actions" if last else f"/actor/actor.{2 * k}/Gemm_output_0"
        nodes.append(gemm(f"/actor/actor.{2 * k}/Gemm", x, wn, bn, y))
        x = y
        if not last:
            a = f"/actor/actor.{2 * k + 1}/{act}"
            nodes.append(helper.make_node(act, [x], [a + "_output_0"], name=a, **(act_attrs or {"alpha": 1.0})))
            x = a + "_output_0"
    return nodes, inits


def io(name, dims):
    return helper.make_tensor_value_info(name, TensorProto.FLOAT, dims)


def model(graph, doc, check=True):
    m = helper.make_model(
        graph,
        opset_imports=[helper.make_opsetid("", OPSET)],
        producer_name=PRODUCER,
        producer_version=PRODUCER_VERSION,
        doc_string=doc,
    )
    m.ir_version = IR_VERSION
    if check:
        onnx.checker.check_model(m, full_check=True)
    return m


def save(m, path):
    data = m.SerializeToString()
    with open(path, "wb") as f:
        f.write(data)
    return data


def gemm(name, a, w, b, out, trans_b=1, trans_a=0):
    attrs = {"alpha": 1.0, "beta": 1.0, "transB": trans_b}
    if trans_a:
        attrs["transA"] = trans_a
    return helper.make_node("Gemm", [a, w, b], [out], name=name, **attrs)


def load_blob_json(path, what):
    with open(path) as f:
        j = json.load(f)
    for layer in j["layers"]:
        if "weight" not in layer:
            sys.exit(f"make_models: {path}: layers carry no weights (use pbppo inspect --json --weights)")
    layers = []
    for layer in j["layers"]:
        w = np.array(layer["weight"], dtype=np.float64).reshape(layer["out"], layer["in"])
        b = np.array(layer["bias"], dtype=np.float64)
        layers.append((w, b, layer["activation"]))
    print(f"make_models: {what}: {j['input_size']} -> " + " -> ".join(f"{l['out']} {l['activation']}" for l in j["layers"]))
    return j, layers


def write_mapping(path, robot, in_name, observations, out_name, actions, header):
    """observations: per ONNX input element, (layout name or None for a constant, constant, comment)."""
    lines = [
        "# How the ONNX model's input and output elements correspond to the robot's IO layout.",
        *[f"# {h}" for h in header],
        f"robot: {robot}",
        f"input: {{name: {in_name}, size: {len(observations)}}}",
        f"output: {{name: {out_name}, size: {len(actions)}}}",
        "observations:",
    ]
    for i, (name, constant, comment) in enumerate(observations):
        entry = f"{{constant: {constant!r}}}" if name is None else name
        note = f"  # {i}" + (f": {comment}" if comment else "")
        lines.append(f"  - {entry:<28}{note}")
    lines.append("actions:")
    for i, (name, comment) in enumerate(actions):
        note = f"  # {i}" + (f": {comment}" if comment else "")
        lines.append(f"  - {name:<28}{note}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


# ----------------------------------------------------------------------------- a. rsl_rl_walk

# legged_gym's observation order for flat terrain; the base linear velocity comes first.
LEGGED_GYM_PREFIX = ["base_lin_vel_x", "base_lin_vel_y", "base_lin_vel_z"]
RSL_RL_HIDDEN = [512, 256, 128]


def rsl_rl_walk(out_dir, flat, flat_layers):
    rng = np.random.default_rng(20240601)
    names = flat["observation_names"]
    n_in = len(LEGGED_GYM_PREFIX) + len(names)  # 48
    assert n_in == 48 and flat["output_size"] == 12
    widths = [n_in] + RSL_RL_HIDDEN + [flat["output_size"]]
    acts = [l[2] for l in flat_layers]
    assert acts[:-1] == ["elu"] * 3 and acts[-1] == "identity" and flat["action_head"] == "linear"
    # The blob's normaliser must be the identity for the weights to carry over unchanged.
    assert all(m == 0.0 for m in flat["normaliser"]["mean"]) and all(s == 1.0 for s in flat["normaliser"]["inv_std"])

    weights = []
    for k, (w, b, _) in enumerate(flat_layers):
        n_out, n_prev = widths[k + 1], widths[k]
        W = np.zeros((n_out, n_prev))
        B = np.zeros(n_out)
        o, i = w.shape
        col0 = len(LEGGED_GYM_PREFIX) if k == 0 else 0
        # flat's weights in the top-left block (after the base_lin_vel columns in layer 0)
        W[:o, col0 : col0 + i] = w
        B[:o] = b
        if k == 0:
            # base_lin_vel columns: small weights; the mapping feeds them 0, so they contribute 0
            W[:o, :col0] = rng.normal(0.0, 0.05, (o, col0))
        if n_out > o:
            # extra hidden units: small random incoming weights and bias; their outgoing weights
            # (the next layer's columns past flat's width) stay exactly 0, so they change nothing
            W[o:, :] = rng.normal(0.0, 0.05, (n_out - o, n_prev))
            B[o:] = rng.normal(0.0, 0.05, n_out - o)
        weights.append((W, B))

    nodes, inits = torch_gemm_chain(weights)
    g = helper.make_graph(nodes, "main_graph", [io("obs", ["batch", n_in])], [io("actions", ["batch", widths[-1]])], inits)
    m = model(
        g,
        "rsl_rl ActorCritic actor (legged_gym flat terrain), 48-512-256-128-12 ELU: "
        "the weights of pbppo's flat.blob with unused extra hidden units",
    )
    save(m, os.path.join(out_dir, "rsl_rl_walk.onnx"))

    obs = [(None, 0.0, f"{n}: no device of the robot measures it") for n in LEGGED_GYM_PREFIX]
    obs += [(n, None, None) for n in names]
    write_mapping(
        os.path.join(out_dir, "rsl_rl_walk.yaml"),
        "quadruped",
        "obs",
        obs,
        "actions",
        [(n, None) for n in flat["action_names"]],
        ["rsl_rl_walk.onnx: legged_gym's 48 flat-terrain inputs; the policy acts like flat.blob."],
    )


# ------------------------------------------------------------------------- b. normalised_walk

# ONNX position -> layout index swaps: a few inputs and two outputs out of the layout's order.
INPUT_SWAPS = [(0, 2), (6, 8), (9, 21), (40, 44)]  # ang_vel x<->z, cmd vx<->yaw, q/dq LF_HAA, 2 last actions
OUTPUT_SWAPS = [(1, 10)]  # LF_HFE <-> RH_HFE


def permutation(n, swaps):
    p = list(range(n))
    for a, b in swaps:
        p[a], p[b] = p[b], p[a]
    return p


def normalised_walk(out_dir, flat, flat_layers):
    rng = np.random.default_rng(20240602)
    names, act_names = flat["observation_names"], flat["action_names"]
    n_in, n_out = len(names), len(act_names)
    perm_in = permutation(n_in, INPUT_SWAPS)  # ONNX input j is layout observation perm_in[j]
    perm_out = permutation(n_out, OUTPUT_SWAPS)  # ONNX output j is layout action perm_out[j]

    mean = f32(rng.normal(0.0, 0.3, n_in)).astype(np.float64)
    std = f32(rng.uniform(0.5, 2.0, n_in)).astype(np.float64)
    div = f32(std + NORMALIZER_EPS).astype(np.float64)  # torch folds std + eps into one constant

    layers = [(w.copy(), b.copy(), a) for w, b, a in flat_layers]
    # layer 0 in ONNX input order, then undo the normaliser: W' = W diag(d), b' = b + W mean
    w0 = layers[0][0][:, perm_in]
    b0 = layers[0][1] + w0 @ mean
    layers[0] = (w0 * div[None, :], b0, layers[0][2])
    wl, bl, al = layers[-1]
    layers[-1] = (wl[perm_out, :], bl[perm_out], al)

    # rsl_rl keeps the running statistics as [1, n] buffers
    nodes, inits = normaliser_nodes(("Sub", "normalizer._mean", mean[None, :]), ("Div", "normalizer._std_eps", div[None, :]), 100.0)
    x = "/normalizer/Clip_output_0"
    for k, (W, B, a) in enumerate(layers):
        idx = 2 * k
        wn, bn = f"actor.{idx}.weight", f"actor.{idx}.bias"
        inits += [init(wn, W), init(bn, B)]
        last = k == len(layers) - 1
        y = "actions" if last else f"/actor/actor.{idx}/Gemm_output_0"
        nodes.append(gemm(f"/actor/actor.{idx}/Gemm", x, wn, bn, y))
        x = y
        if not last:
            assert a == "elu"
            e = f"/actor/actor.{idx + 1}/Elu_output_0"
            nodes.append(helper.make_node("Elu", [x], [e], name=f"/actor/actor.{idx + 1}/Elu", alpha=1.0))
            x = e
    g = helper.make_graph(nodes, "main_graph", [io("obs", ["batch", n_in])], [io("actions", ["batch", n_out])], inits)
    m = model(
        g,
        "rsl_rl ActorCritic actor behind EmpiricalNormalization (clipped at 100), 45-128-64-32-12 ELU: "
        "computes what pbppo's flat.blob computes, inputs and outputs partly reordered",
    )
    save(m, os.path.join(out_dir, "normalised_walk.onnx"))

    moved_in = {j for s in INPUT_SWAPS for j in s}
    moved_out = {j for s in OUTPUT_SWAPS for j in s}
    write_mapping(
        os.path.join(out_dir, "normalised_walk.yaml"),
        "quadruped",
        "obs",
        [(names[perm_in[j]], None, "moved" if j in moved_in else None) for j in range(n_in)],
        "actions",
        [(act_names[perm_out[j]], "moved" if j in moved_out else None) for j in range(n_out)],
        [
            "normalised_walk.onnx: flat.blob's inputs and outputs in the layout's order except the ones",
            "marked 'moved' (swapped in pairs); the model normalises its inputs itself.",
        ],
    )
    return perm_in, perm_out


# ---------------------------------------------------------------------------------- c. sb3_auv


def sb3_auv(out_dir, auv, auv_layers, layout_actions):
    norm = auv["normaliser"]
    mean = np.array(norm["mean"], dtype=np.float64)
    inv_std = f32(norm["inv_std"]).astype(np.float64)
    clip = float(norm["clip"])
    acts = [l[2] for l in auv_layers]
    assert acts == ["tanh", "tanh", "identity"] and auv["action_head"] == "linear", acts

    # Does the blob's action map already clamp the policy output y to a box? The map is
    # clamp(y * scale + offset, low, high); with scale > 0 it is the same as clamping y to
    # [(low - offset) / scale, (high - offset) / scale] first.
    amap = auv["action_map"]
    bounds = []
    for i, name in enumerate(auv["action_names"]):
        s, o, lo, hi = (float(amap[k][i]) for k in ("scale", "offset", "low", "high"))
        la = layout_actions.get(name)
        assert la is not None and abs(la["scale"] - s) < 1e-6 and abs(la["offset"] - o) < 1e-6, (name, la)
        assert abs(la["low"] - lo) < 1e-6 and abs(la["high"] - hi) < 1e-6, (name, la)
        assert s > 0
        bounds.append(((lo - o) / s, (hi - o) / s))
    clip_out = all(abs(lo + 1.0) < 1e-9 and abs(hi - 1.0) < 1e-9 for lo, hi in bounds)
    print(f"make_models: auv action map clamps the policy output to {bounds}: output Clip(-1, 1) {'emitted' if clip_out else 'left out'}")

    nodes, inits = normaliser_nodes(("Mul", "normalizer.inv_std", inv_std), ("Add", "normalizer.shift", -mean * inv_std), clip)
    # torch exports Linear on a non-2-D input as MatMul(x, W^T) then Add(bias, x): bias first
    scopes = ["/mlp_extractor/policy_net/policy_net.0", "/mlp_extractor/policy_net/policy_net.2", "/action_net"]
    bias_names = ["mlp_extractor.policy_net.0.bias", "mlp_extractor.policy_net.2.bias", "action_net.bias"]
    x = "/normalizer/Clip_output_0"
    for k, (w, b, a) in enumerate(auv_layers):
        wn = f"onnx::MatMul_{101 + k}"  # torch's name for a transposed weight constant
        inits += [init(wn, w.T), init(bias_names[k], b)]
        mm = f"{scopes[k]}/MatMul_output_0"
        nodes.append(helper.make_node("MatMul", [x, wn], [mm], name=f"{scopes[k]}/MatMul"))
        last = k == len(auv_layers) - 1
        y = ("/action_net/Add_output_0" if clip_out else "actions") if last else f"{scopes[k]}/Add_output_0"
        nodes.append(helper.make_node("Add", [bias_names[k], mm], [y], name=f"{scopes[k]}/Add"))
        x = y
        if not last:
            t = f"/mlp_extractor/policy_net/policy_net.{2 * k + 1}/Tanh"
            nodes.append(helper.make_node("Tanh", [x], [t + "_output_0"], name=t))
            x = t + "_output_0"
    if clip_out:
        nodes.append(helper.make_node("Clip", [x, "/Constant_output_0", "/Constant_1_output_0"], ["actions"], name="/Clip"))
        inits += [scalar("/Constant_output_0", -1.0), scalar("/Constant_1_output_0", 1.0)]
    n_in, n_out = auv["input_size"], auv["output_size"]
    g = helper.make_graph(nodes, "main_graph", [io("obs", ["batch", n_in])], [io("actions", ["batch", n_out])], inits)
    m = model(
        g,
        "stable-baselines3 PPO MlpPolicy actor, 64-64 tanh, with its VecNormalize statistics folded in: "
        "the weights of pbppo's auv_nav.blob",
    )
    save(m, os.path.join(out_dir, "sb3_auv.onnx"))
    write_mapping(
        os.path.join(out_dir, "sb3_auv.yaml"),
        "auv",
        "obs",
        [(n, None, None) for n in auv["observation_names"]],
        "actions",
        [(n, None) for n in auv["action_names"]],
        ["sb3_auv.onnx: auv_nav.blob's inputs and outputs in the layout's order."]
        + (
            [
                "Its output Clip(-1, 1) is the box the layout's action map (v: 0.75 a + 0.75 in [0, 1.5];",
                "omega: 0.5 a in [-0.5, 0.5]) clamps the policy output to anyway.",
            ]
            if clip_out
            else ["No output Clip: the layout's action map does not clamp the policy output to [-1, 1]."]
        ),
    )
    return clip_out


# -------------------------------------------------------------------------- d. leaky_tanh_head


def leaky_tanh_head(out_dir):
    """6-16-16-3, LeakyReLU(0.2) hidden, then Tanh, Mul(scale), Add(offset) at the output.

    A clean import gives a 6-16-16-3 blob with leaky_relu(0.2) hidden activations, identity
    normaliser, tanh action head and the action map's scale/offset from the Mul/Add vectors
    (low/high from the synthetic layout). The first Gemm stores its weight as [in][out]
    (transB=0), the others as [out][in] (transB=1), so both layouts are exercised.
    """
    rng = np.random.default_rng(20240604)
    widths = [6, 16, 16, 3]
    nodes, inits = [], []
    x = "obs"
    for k in range(3):
        w = rng.normal(0.0, 1.0 / np.sqrt(widths[k]), (widths[k + 1], widths[k]))
        b = rng.normal(0.0, 0.1, widths[k + 1])
        trans_b = 0 if k == 0 else 1
        wn, bn = f"actor.{2 * k}.weight", f"actor.{2 * k}.bias"
        inits += [init(wn, w if trans_b else w.T), init(bn, b)]
        y = f"/actor/actor.{2 * k}/Gemm_output_0"
        nodes.append(gemm(f"/actor/actor.{2 * k}/Gemm", x, wn, bn, y, trans_b=trans_b))
        x = y
        if k < 2:
            a = f"/actor/actor.{2 * k + 1}/LeakyRelu"
            nodes.append(helper.make_node("LeakyRelu", [x], [a + "_output_0"], name=a, alpha=0.2))
            x = a + "_output_0"
    nodes.append(helper.make_node("Tanh", [x], ["/Tanh_output_0"], name="/Tanh"))
    nodes.append(helper.make_node("Mul", ["/Tanh_output_0", "action_scale"], ["/Mul_output_0"], name="/Mul"))
    nodes.append(helper.make_node("Add", ["/Mul_output_0", "action_offset"], ["actions"], name="/Add"))
    inits += [init("action_scale", [0.5, 2.0, 0.25]), init("action_offset", [0.1, -0.3, 0.0])]
    g = helper.make_graph(nodes, "main_graph", [io("obs", ["batch", 6])], [io("actions", ["batch", 3])], inits)
    m = model(g, "importer unit test: 6-16-16-3 LeakyReLU(0.2), tanh head with scale and offset, random weights")
    return save(m, os.path.join(out_dir, "leaky_tanh_head.onnx"))


# ---------------------------------------------------------------------------- e. stacked history

HISTORY_TERMS = [["p"], ["v0", "v1"]]
HISTORY_LENGTH = 4
# What each output reads, as (weight, element, steps ago).
HISTORY_OUTPUTS = [[(1.0, "p", 0), (0.5, "v1", 3)], [(1.0, "v0", 1), (-1.0, "v1", 2)]]


def history_index(order, oldest_first, element, lag):
    """Where `element` `lag` policy steps ago sits in the stacked input: this script's own
    statement of the two orders. Frame position f counts from the first frame in the input; with
    the oldest first it holds the frame HISTORY_LENGTH-1-f steps ago, else f steps ago."""
    f = HISTORY_LENGTH - 1 - lag if oldest_first else lag
    frame = [e for term in HISTORY_TERMS for e in term]
    if order == "frame-major":
        return f * len(frame) + frame.index(element)
    start = 0
    for term in HISTORY_TERMS:
        if element in term:
            return start + f * len(term) + term.index(element)
        start += HISTORY_LENGTH * len(term)
    raise KeyError(element)


def stacked_history(out_dir, name, order, oldest_first):
    n = HISTORY_LENGTH * sum(len(t) for t in HISTORY_TERMS)
    w = np.zeros((len(HISTORY_OUTPUTS), n))
    for o, reads in enumerate(HISTORY_OUTPUTS):
        for weight, element, lag in reads:
            w[o, history_index(order, oldest_first, element, lag)] = weight
    nodes = [gemm("/actor/actor.0/Gemm", "obs", "actor.0.weight", "actor.0.bias", "actions")]
    inits = [init("actor.0.weight", w), init("actor.0.bias", np.zeros(len(HISTORY_OUTPUTS)))]
    g = helper.make_graph(nodes, "main_graph", [io("obs", ["batch", n])], [io("actions", ["batch", 2])], inits)
    oldest = "first" if oldest_first else "last"
    save(model(g, f"stacked history, {order}, oldest frame {oldest}: outputs read named frames"),
         os.path.join(out_dir, name + ".onnx"))
    terms = ", ".join(t[0] if len(t) == 1 else "[" + ", ".join(t) + "]" for t in HISTORY_TERMS)
    with open(os.path.join(out_dir, name + ".yaml"), "w") as f:
        f.write(
            f"# {HISTORY_LENGTH} stacked frames, {order}, oldest {oldest}\n"
            "robot: histbot\n"
            f"input: {{name: obs, size: {n}}}\n"
            "output: {name: actions, size: 2}\n"
            f"history: {{length: {HISTORY_LENGTH}, order: {order}, oldest: {oldest}}}\n"
            f"observations: [{terms}]\n"
            "actions: [a0, a1]\n"
        )



# ------------------------------------------------------------------------- g. recurrent actors

# The recurrent state as torch.onnx.export writes an nn.LSTM / nn.GRU of rsl_rl's ActorCriticRecurrent
# actor (its exporter: obs, h_in, c_in -> actions, h_out, c_out): Unsqueeze(obs, 0) -> X [1, batch, n];
# the node's Y [1, 1, batch, H] -> Squeeze(1) -> Squeeze(0) -> the MLP head; initial_h / initial_c are
# the graph inputs (one layer) or Slices of them (stacked), Y_h / Y_c the graph outputs (or Concats).
# torch's gate order is converted to ONNX's on export: LSTM i, o, f, c; GRU z, r, h.


def axes_const(name, axes):
    return numpy_helper.from_array(np.array(axes, dtype=np.int64), name)


def recurrent_node(kind, prefix, x, w, r, b, h0, c0, y, yh, yc, hidden, lbr=None, **extra):
    inputs = [x, w, r, b, "", h0] + ([c0] if kind == "LSTM" else [])
    outputs = [y, yh] + ([yc] if kind == "LSTM" else [])
    attrs = {"hidden_size": hidden}
    if kind == "GRU" and lbr is not None:
        attrs["linear_before_reset"] = lbr
    attrs.update(extra)
    return helper.make_node(kind, inputs, outputs, name=f"{prefix}/{kind}", **attrs)


def torch_rnn_weights(rng, kind, n_in, hidden):
    """W [1, G*H, n_in], R [1, G*H, H], B [1, 2*G*H], uniform in +-1/sqrt(H) as torch initialises them."""
    g = 4 if kind == "LSTM" else 3
    k = 1.0 / np.sqrt(hidden)
    return (
        rng.uniform(-k, k, (1, g * hidden, n_in)),
        rng.uniform(-k, k, (1, g * hidden, hidden)),
        rng.uniform(-k, k, (1, 2 * g * hidden)),
    )


def recurrent_graph(kind, n_in, layers, hidden, head, rng, lbr=None, pre_nodes=None, pre_inits=None, first_in=None,
                    rnn_weights=None):
    """obs [-> pre_nodes] -> Unsqueeze -> `layers` stacked `kind` layers of `hidden` -> Squeeze(1), Squeeze(0)
    -> the head (torch_gemm_chain over the hidden state). Returns the graph."""
    nodes, inits = list(pre_nodes or []), list(pre_inits or [])
    x_in = nodes[-1].output[0] if nodes else "obs"
    inits += [axes_const("/memory_a/Constant_output_0", [0]), axes_const("/memory_a/Constant_1_output_0", [1])]
    nodes.append(helper.make_node("Unsqueeze", [x_in, "/memory_a/Constant_output_0"], ["/memory_a/Unsqueeze_output_0"],
                                  name="/memory_a/Unsqueeze"))
    x = "/memory_a/Unsqueeze_output_0"
    width = first_in or n_in
    state_names = ["h"] + (["c"] if kind == "LSTM" else [])
    outs = {s: [] for s in state_names}
    for layer in range(layers):
        pre = f"/memory_a/rnn/l{layer}" if layers > 1 else "/memory_a/rnn"
        w, r, b = rnn_weights[layer] if rnn_weights else torch_rnn_weights(rng, kind, width, hidden)
        wn, rn, bn = f"onnx::{kind}_W_{layer}", f"onnx::{kind}_R_{layer}", f"onnx::{kind}_B_{layer}"
        inits += [init(wn, w), init(rn, r), init(bn, b)]
        state_in = {}
        for s_ in state_names:
            if layers == 1:
                state_in[s_] = f"{s_}_in"
            else:  # torch: Slice(state, starts [layer], ends [layer + 1], axes [0])
                st, en, ax = f"{pre}/{s_}_starts", f"{pre}/{s_}_ends", f"{pre}/{s_}_axes"
                inits += [axes_const(st, [layer]), axes_const(en, [layer + 1]), axes_const(ax, [0])]
                state_in[s_] = f"{pre}/Slice_{s_}_output_0"
                nodes.append(helper.make_node("Slice", [f"{s_}_in", st, en, ax], [state_in[s_]], name=f"{pre}/Slice_{s_}"))
        y = f"{pre}/{kind}_output_0"
        yh = "h_out" if layers == 1 else f"{pre}/{kind}_output_1"
        yc = "c_out" if layers == 1 else f"{pre}/{kind}_output_2"
        nodes.append(recurrent_node(kind, pre, x, wn, rn, bn, state_in["h"], state_in.get("c"), y, yh, yc, hidden, lbr))
        outs["h"].append(yh)
        if kind == "LSTM":
            outs["c"].append(yc)
        sq = f"{pre}/Squeeze_output_0"
        nodes.append(helper.make_node("Squeeze", [y, "/memory_a/Constant_1_output_0"], [sq], name=f"{pre}/Squeeze"))
        x, width = sq, hidden
    if layers > 1:
        for s_ in state_names:
            nodes.append(helper.make_node("Concat", outs[s_], [f"{s_}_out"], name=f"/memory_a/Concat_{s_}", axis=0))
    nodes.append(helper.make_node("Squeeze", [x, "/memory_a/Constant_output_0"], ["/memory_a/Squeeze_output_0"],
                                  name="/memory_a/Squeeze"))
    head_nodes, head_inits = torch_gemm_chain(head)
    head_nodes[0].input[0] = "/memory_a/Squeeze_output_0"
    nodes += head_nodes
    inits += head_inits
    inputs = [io("obs", ["batch", n_in])] + [io(f"{s_}_in", [layers, "batch", hidden]) for s_ in state_names]
    outputs = [io("actions", ["batch", head[-1][0].shape[0]])] + [
        io(f"{s_}_out", [layers, "batch", hidden]) for s_ in state_names
    ]
    return helper.make_graph(nodes, "main_graph", inputs, outputs, inits)


def write_recurrent_mapping(path, flat, kind, header):
    states = ["h"] + (["c"] if kind == "LSTM" else [])
    write_mapping(path, "quadruped", "obs", [(n, None, None) for n in flat["observation_names"]], "actions",
                  [(n, None) for n in flat["action_names"]], header)
    with open(path, "a") as f:
        f.write("state:  # the recurrent state: each output fed back to its input at the next step\n")
        for s_ in states:
            f.write(f"  - {{input: {s_}_in, output: {s_}_out}}\n")


# The walking LSTM: flat.blob (45-128-64-32-12 ELU) with its second layer run by an LSTM. The LSTM's
# cell input is eps * (W2 x + b2), its input and output gates held open (bias 12), its forget gate at
# sigmoid(-4) = 0.018 of the previous cell; h = o * tanh(c) ~ eps * (z + 0.018 z_prev ...), and a
# 64-64 layer of weight I / eps with ELU gives back ELU(z) with a little of the steps before: it
# walks as flat.blob does, its state carried from step to step (zero at arming).
LSTM_WALK_EPS = 1e-3


def lstm_walk(out_dir, flat, flat_layers):
    rng = np.random.default_rng(20261128)
    (w1, b1, a1), (w2, b2, a2), (w3, b3, a3), (w4, b4, a4) = flat_layers
    assert (a1, a2, a3, a4) == ("elu", "elu", "elu", "identity") and flat["action_head"] == "linear"
    assert all(m == 0.0 for m in flat["normaliser"]["mean"]) and all(s == 1.0 for s in flat["normaliser"]["inv_std"])
    n_in, n1, hidden = w1.shape[1], w1.shape[0], w2.shape[0]
    eps = LSTM_WALK_EPS
    W = np.zeros((1, 4 * hidden, n1))
    R = np.zeros((1, 4 * hidden, hidden))
    B = np.zeros((1, 8 * hidden))
    gate = {"i": 0, "o": 1, "f": 2, "c": 3}  # ONNX order
    for name, bias in (("i", 12.0), ("o", 12.0), ("f", -4.0)):
        k = gate[name]
        B[0, k * hidden:(k + 1) * hidden] = bias
        R[0, k * hidden:(k + 1) * hidden, :] = rng.normal(0.0, 0.5, (hidden, hidden))
    k = gate["c"]
    W[0, k * hidden:(k + 1) * hidden, :] = eps * w2
    B[0, k * hidden:(k + 1) * hidden] = eps * b2
    pre, pre_inits = torch_gemm_chain([(w1, b1)])
    # torch_gemm_chain's single layer writes "actions": rename it to the first layer's output, then ELU
    pre[0].output[0] = "/actor_in/Gemm_output_0"
    pre[0].name = "/actor_in/Gemm"
    for t in pre_inits:
        t.name = t.name.replace("actor.0", "actor_in.0")
    pre[0].input[1], pre[0].input[2] = "actor_in.0.weight", "actor_in.0.bias"
    pre.append(helper.make_node("Elu", ["/actor_in/Gemm_output_0"], ["/actor_in/Elu_output_0"], name="/actor_in/Elu",
                                alpha=1.0))
    head = [(np.eye(hidden) / eps, np.zeros(hidden)), (w3, b3), (w4, b4)]
    g = recurrent_graph("LSTM", n_in, 1, hidden, head, rng, pre_nodes=pre, pre_inits=pre_inits, first_in=n1,
                        rnn_weights=[(W, R, B)])
    save(model(g, "a walking LSTM actor built from flat.blob: 45-128 ELU, LSTM 64 (state h, c), 64-64 ELU, 64-32 ELU, "
                  "32-12"), os.path.join(out_dir, "lstm_walk.onnx"))
    write_recurrent_mapping(os.path.join(out_dir, "lstm_walk.yaml"), flat, "LSTM",
                            ["lstm_walk.onnx: flat.blob's second layer as an LSTM; it walks as flat.blob does."])


def random_recurrent(out_dir, flat, name, seed, kind, hidden, layers=1, lbr=None, normalise=False, head_act="Elu"):
    rng = np.random.default_rng(seed)
    n_in, n_out = len(flat["observation_names"]), len(flat["action_names"])
    pre, pre_inits = None, None
    if normalise:  # rsl_rl's EmpiricalNormalization without a clip: Sub mean, Div std (folded into W)
        pre = [helper.make_node("Sub", ["obs", "normalizer.mean"], ["/normalizer/Sub_output_0"], name="/normalizer/Sub"),
               helper.make_node("Div", ["/normalizer/Sub_output_0", "normalizer.std"], ["/normalizer/Div_output_0"],
                                name="/normalizer/Div")]
        pre_inits = [init("normalizer.mean", rng.normal(0.0, 0.3, (1, n_in))),
                     init("normalizer.std", rng.uniform(0.5, 2.0, (1, n_in)))]
    head = [(rng.normal(0.0, 0.3, (16, hidden)), rng.normal(0.0, 0.1, 16)),
            (rng.normal(0.0, 0.3, (n_out, 16)), rng.normal(0.0, 0.1, n_out))]
    g = recurrent_graph(kind, n_in, layers, hidden, head, rng, lbr=lbr, pre_nodes=pre, pre_inits=pre_inits)
    if head_act != "Elu":
        for n in g.node:
            if n.op_type == "Elu" and n.name.startswith("/actor/"):
                n.op_type = head_act
                del n.attribute[:]
                n.name = n.name.replace("Elu", head_act)
    save(model(g, f"{kind} {hidden} x {layers} on random weights (torch's initialisation), head 16 {head_act}"),
         os.path.join(out_dir, name + ".onnx"))
    write_recurrent_mapping(os.path.join(out_dir, name + ".yaml"), flat, kind,
                            [f"{name}.onnx: the quadruped layout's 45 observations in order, 12 actions."])


def recurrent_models(out_dir, flat, flat_layers):
    lstm_walk(out_dir, flat, flat_layers)
    random_recurrent(out_dir, flat, "gru_actor", 20261129, "GRU", 32, lbr=1)
    random_recurrent(out_dir, flat, "gru_lbr0", 20261130, "GRU", 24, lbr=0, normalise=True, head_act="Tanh")
    random_recurrent(out_dir, flat, "lstm_stacked", 20261131, "LSTM", 24, layers=2)


# ------------------------------------------------------------------------- h. a deploy file

# unitree_rl_lab's export (deploy.yaml beside policy.onnx) of flat.blob as if trained in Isaac Lab:
# the articulation's joint order breadth first (every HAA, then every HFE, then every KFE), so
# joint_ids_map permutes; observation terms in Isaac Lab's order, base_ang_vel and
# projected_gravity with 2 frames of history (term-major, oldest first; the older frame's weights
# 0), clip [-100, 100] before the scale; actions scaled 0.25 about the default pose.
UNITREE_JOINT_ORDER = [f"{leg}_{j}" for j in ("HAA", "HFE", "KFE") for leg in ("LF", "RF", "LH", "RH")]
UNITREE_TERMS = [  # name, width, scale, history, flat's first column (per policy joint for joint terms)
    ("base_ang_vel", 3, [0.25] * 3, 2, 0),
    ("projected_gravity", 3, [1.0] * 3, 2, 3),
    ("velocity_commands", 3, [2.0, 2.0, 0.25], 1, 6),
    ("joint_pos_rel", 12, [1.0] * 12, 1, 9),
    ("joint_vel_rel", 12, [0.05] * 12, 1, 21),
    ("last_action", 12, [1.0] * 12, 1, 33),
]


def unitree_walk(out_dir, flat, flat_layers, quad_actions):
    robot_joints = [n[len("last_action_"):] for n in flat["observation_names"] if n.startswith("last_action_")]
    assert flat["action_names"] == robot_joints and len(robot_joints) == 12
    motor = [robot_joints.index(j) for j in UNITREE_JOINT_ORDER]  # joint_ids_map
    (w1, b1, _), *rest = flat_layers
    columns = []  # per model input: flat's column, or None (an older frame: weight 0)
    for name, width, _, history, col0 in UNITREE_TERMS:
        for frame in range(history):  # oldest first
            for k in range(width):
                col = col0 + (motor[k] if width == 12 else k)
                columns.append(col if frame == history - 1 else None)
    W1 = np.zeros((w1.shape[0], len(columns)))
    for i, col in enumerate(columns):
        if col is not None:
            W1[:, i] = w1[:, col]
    (w4, b4, _) = rest[-1]
    layers = [(W1, b1)] + [(w, b) for (w, b, _) in rest[:-1]] + [(w4[motor, :], b4[motor])]
    nodes, inits = torch_gemm_chain(layers)
    g = helper.make_graph(nodes, "main_graph", [io("obs", ["batch", len(columns)])], [io("actions", ["batch", 12])],
                          inits)
    save(model(g, "flat.blob exported as unitree_rl_lab exports an Isaac Lab policy (deploy.yaml beside it)"),
         os.path.join(out_dir, "unitree_walk.onnx"))
    # The default pose: the quadruped layout's action offsets (its io_layout.yaml).
    offsets = {j: quad_actions[j]["offset"] for j in robot_joints}
    lines = [
        "# unitree_rl_lab's deploy.yaml for unitree_walk.onnx (written by tools/onnx/make_models.py)",
        "joint_ids_map: [" + ", ".join(str(m) for m in motor) + "]",
        "step_dt: 0.02",
        "stiffness: [" + ", ".join(["20.0"] * 12) + "]",
        "damping: [" + ", ".join(["0.5"] * 12) + "]",
        "default_joint_pos: [" + ", ".join(repr(offsets[j]) for j in UNITREE_JOINT_ORDER) + "]",
        "commands:",
        "  base_velocity:",
        "    ranges:",
        "      lin_vel_x: [-1.0, 1.0]",
        "      lin_vel_y: [-0.5, 0.5]",
        "      ang_vel_z: [-1.0, 1.0]",
        "      heading: null",
        "actions:",
        "  JointPositionAction:",
        "    clip: null",
        "    joint_names: [.*]",
        "    scale: [" + ", ".join(["0.25"] * 12) + "]",
        "    offset: [" + ", ".join(repr(offsets[j]) for j in UNITREE_JOINT_ORDER) + "]",
        "    joint_ids: null",
        "observations:",
    ]
    for name, width, scale, history, _ in UNITREE_TERMS:
        lines += [f"  {name}:",
                  "    params: {command_name: base_velocity}" if name == "velocity_commands" else "    params: {}",
                  "    clip: [-100.0, 100.0]",
                  "    scale: [" + ", ".join(repr(x) for x in scale) + "]",
                  f"    history_length: {history}"]
    with open(os.path.join(out_dir, "unitree_walk.deploy.yaml"), "w") as f:
        f.write("\n".join(lines) + "\n")
    isaac_env(out_dir, offsets)
    isaac_agent(out_dir, [w.shape[0] for (w, _, _) in flat_layers[:-1]], flat_layers[0][2])


def isaac_agent(out_dir, hidden, activation):
    """The same run's rsl_rl runner settings as Isaac Lab dumps them (params/agent.yaml, rsl_rl 2.3's
    fields, abridged): an MLP actor of flat.blob's hidden widths, no observation normaliser, no
    action clip."""
    t = "seed: 42\ndevice: cuda:0\nnum_steps_per_env: 24\nmax_iterations: 1500\nempirical_normalization: false\n"
    t += "obs_groups:\n  policy:\n  - policy\n  critic:\n  - policy\n  - critic\nclip_actions: null\n"
    t += "save_interval: 50\nexperiment_name: quadruped_flat\nrun_name: ''\nlogger: tensorboard\nresume: false\n"
    t += "class_name: OnPolicyRunner\npolicy:\n  class_name: ActorCritic\n  init_noise_std: 1.0\n"
    t += "  noise_std_type: scalar\n  actor_obs_normalization: false\n  critic_obs_normalization: false\n"
    t += "  actor_hidden_dims:\n" + "".join(f"  - {h}\n" for h in hidden)
    t += "  critic_hidden_dims:\n  - 512\n  - 256\n  - 128\n"
    t += f"  activation: {activation}\n"
    t += "algorithm:\n  class_name: PPO\n  num_learning_epochs: 5\n  num_mini_batches: 4\n  learning_rate: 0.001\n"
    t += "  schedule: adaptive\n  gamma: 0.99\n  lam: 0.95\n  entropy_coef: 0.01\n  desired_kl: 0.01\n"
    t += "  max_grad_norm: 1.0\n  value_loss_coef: 1.0\n  use_clipped_value_loss: true\n  clip_param: 0.2\n"
    with open(os.path.join(out_dir, "unitree_walk.agent.yaml"), "w") as f:
        f.write("# rsl_rl's params/agent.yaml for unitree_walk.onnx (written by tools/onnx/make_models.py)\n" + t)


def isaac_env(out_dir, offsets):
    """The same policy's Isaac Lab params/env.yaml (as ManagerBasedRLEnvCfg dumps it, abridged: the
    fields the importer reads and a few it skips, PyYAML's python tags included)."""
    def tup(values, indent):
        return " !!python/tuple\n" + "".join(f"{' ' * indent}- {v!r}\n" for v in values)

    pose = {".*_HAA": 0.0}
    for side, legs in (("(LF|RF)", ("LF", "RF")), ("(LH|RH)", ("LH", "RH"))):
        for j in ("HFE", "KFE"):
            pose[f"{side}_{j}"] = offsets[f"{legs[0]}_{j}"]
    t = "viewer:\n  eye:" + tup([7.5, 7.5, 7.5], 2) + "  origin_type: world\n"
    t += "sim:\n  physics_prim_path: /physicsScene\n  device: cuda:0\n  dt: 0.005\n  render_interval: 4\n"
    t += "  gravity:" + tup([0.0, 0.0, -9.81], 2)
    t += "seed: 42\ndecimation: 4\n"
    t += "scene:\n  num_envs: 4096\n  robot:\n    class_type: isaaclab.assets.articulation.articulation:Articulation\n"
    t += "    prim_path: /World/envs/env_.*/Robot\n    init_state:\n      pos:" + tup([0.0, 0.0, 0.5], 6)
    t += "      joint_pos:\n" + "".join(f"        {k}: {v!r}\n" for k, v in pose.items())
    t += "      joint_vel:\n        .*: 0.0\n"
    t += "    actuators:\n      legs:\n        class_type: isaaclab.actuators.actuator_pd:ImplicitActuator\n"
    t += "        joint_names_expr:\n        - .*_HAA\n        - .*_HFE\n        - .*_KFE\n"
    t += "        effort_limit: null\n        stiffness: 20.0\n        damping: 0.5\n        armature: 0.01\n"
    t += "observations:\n  policy:\n    concatenate_terms: true\n    concatenate_dim: -1\n"
    t += "    enable_corruption: true\n    history_length: null\n    flatten_history_dim: true\n"
    funcs = {"base_ang_vel": "base_ang_vel", "projected_gravity": "projected_gravity",
             "velocity_commands": "generated_commands", "joint_pos_rel": "joint_pos_rel",
             "joint_vel_rel": "joint_vel_rel", "last_action": "last_action"}
    for name, width, scale, history, _ in UNITREE_TERMS:
        t += f"    {name}:\n      func: isaaclab.envs.mdp.observations:{funcs[name]}\n"
        t += ("      params:\n        command_name: base_velocity\n" if name == "velocity_commands"
              else "      params: {}\n")
        t += "      modifiers: null\n"
        t += "      noise:\n        func: isaaclab.utils.noise.noise_model:uniform_noise\n        operation: add\n"
        t += "        n_min: -0.05\n        n_max: 0.05\n"
        t += "      clip:" + tup([-100.0, 100.0], 6)
        t += ("      scale: " + repr(scale[0]) + "\n") if len(set(scale)) == 1 else ("      scale:" + tup(scale, 6))
        t += f"      history_length: {history if history > 1 else 0}\n      flatten_history_dim: true\n"
    t += "  critic:\n    concatenate_terms: true\n    base_lin_vel:\n"
    t += "      func: isaaclab.envs.mdp.observations:base_lin_vel\n      params: {}\n"
    t += "actions:\n  joint_pos:\n    class_type: isaaclab.envs.mdp.actions.joint_actions:JointPositionAction\n"
    t += "    asset_name: robot\n    debug_vis: false\n    clip: null\n    joint_names:\n    - .*\n"
    t += "    scale: 0.25\n    offset: 0.0\n    preserve_order: false\n    use_default_offset: true\n"
    t += "commands:\n  base_velocity:\n    class_type: isaaclab.envs.mdp.commands.velocity_command:UniformVelocityCommand\n"
    t += "    ranges:\n      lin_vel_x:" + tup([-1.0, 1.0], 6) + "      lin_vel_y:" + tup([-0.5, 0.5], 6)
    t += "      ang_vel_z:" + tup([-1.0, 1.0], 6) + "      heading: null\n"
    with open(os.path.join(out_dir, "unitree_walk.env.yaml"), "w") as f:
        f.write("# Isaac Lab's params/env.yaml for unitree_walk.onnx (written by tools/onnx/make_models.py)\n" + t)


# ------------------------------------------------------------------------------- f. bad models


def small_layers(rng, widths):
    out = []
    for k in range(len(widths) - 1):
        out.append((rng.normal(0.0, 0.5, (widths[k + 1], widths[k])), rng.normal(0.0, 0.1, widths[k + 1])))
    return out


def small_actor(rng, widths=(4, 8, 2), in_dims=None, act="Elu", act_attrs=None, tweak=None):
    """A torch-named Gemm/ELU chain; `tweak(nodes, inits, inputs, outputs)` breaks it in place."""
    nodes, inits = torch_gemm_chain(small_layers(rng, list(widths)), act, act_attrs)
    inputs = [io("obs", in_dims or ["batch", widths[0]])]
    outputs = [io("actions", ["batch", widths[-1]])]
    if tweak:
        tweak(nodes, inits, inputs, outputs)
    return helper.make_graph(nodes, "main_graph", inputs, outputs, inits)


def node_named(nodes, name):
    return next(n for n in nodes if n.name == name)


def parses(data):
    try:
        onnx.ModelProto().ParseFromString(data)
        return True
    except Exception:  # the protobuf DecodeError
        return False


def bad_models(out_dir, good_small_bytes, flat):
    bad = os.path.join(out_dir, "bad")
    os.makedirs(bad, exist_ok=True)
    rows = []  # (file, what is wrong, what the error must name)

    def write(name, g, wrong, must_name, check=True):
        m = model(g, f"importer refusal test: {wrong}", check=False)
        if check:
            onnx.checker.check_model(m)  # valid ONNX: the refusal is the importer's own rule
        save(m, os.path.join(bad, name))
        rows.append((name, wrong, must_name))

    # truncated: the first 60% of a good model's bytes (cut inside an initializer's raw data)
    cut = good_small_bytes[: int(len(good_small_bytes) * 0.6)]
    assert not parses(cut), "truncated model still parses"
    with open(os.path.join(bad, "truncated.onnx"), "wb") as f:
        f.write(cut)
    rows.append(
        (
            "truncated.onnx",
            f"the first 60% ({len(cut)} of {len(good_small_bytes)} bytes) of leaky_tanh_head.onnx: not a complete protobuf",
            "the file path (a parse error; no node)",
        )
    )

    # garbage: random bytes
    grng = np.random.default_rng(20240605)
    junk = grng.integers(0, 256, 777, dtype=np.uint8).tobytes()
    assert not parses(junk), "garbage parses as a model"
    with open(os.path.join(bad, "garbage.onnx"), "wb") as f:
        f.write(junk)
    rows.append(("garbage.onnx", "777 random bytes: not an ONNX protobuf", "the file path (a parse error; no node)"))

    rng = np.random.default_rng(20240606)

    def softmax(nodes, inits, inputs, outputs):
        # obs -> Gemm -> Softmax -> Gemm: the Softmax takes the ELU's place in the chain
        i = nodes.index(node_named(nodes, "/actor/actor.1/Elu"))
        nodes[i] = helper.make_node("Softmax", list(nodes[i].input), list(nodes[i].output), name="actor.softmax", axis=1)

    write(
        "unsupported_op.onnx",
        small_actor(rng, tweak=softmax),
        "a Softmax node between the two Gemms (4-8-2)",
        "node 'actor.softmax', op Softmax",
    )

    def lstm(nodes, inits, inputs, outputs):
        # rsl_rl's recurrent actor: obs -> Unsqueeze -> LSTM(4 -> 8) -> Squeeze -> Gemm(8 -> 2)
        h = 8
        w = rng.normal(0.0, 0.3, (1, 4 * h, 4))
        r = rng.normal(0.0, 0.3, (1, 4 * h, h))
        bb = rng.normal(0.0, 0.1, (1, 8 * h))
        del nodes[:]
        del inits[:]
        inits += [
            numpy_helper.from_array(np.array([0], dtype=np.int64), "/memory_a/Constant_output_0"),
            numpy_helper.from_array(np.array([0, 1], dtype=np.int64), "/memory_a/Constant_1_output_0"),
            init("onnx::LSTM_W", w),
            init("onnx::LSTM_R", r),
            init("onnx::LSTM_B", bb),
            init("actor.0.weight", rng.normal(0.0, 0.5, (2, h))),
            init("actor.0.bias", rng.normal(0.0, 0.1, 2)),
        ]
        nodes += [
            helper.make_node(
                "Unsqueeze", ["obs", "/memory_a/Constant_output_0"], ["/memory_a/Unsqueeze_output_0"], name="/memory_a/Unsqueeze"
            ),
            helper.make_node(
                "LSTM",
                ["/memory_a/Unsqueeze_output_0", "onnx::LSTM_W", "onnx::LSTM_R", "onnx::LSTM_B"],
                ["/memory_a/rnn/LSTM_output_0"],
                name="/memory_a/rnn/LSTM",
                hidden_size=h,
            ),
            helper.make_node(
                "Squeeze",
                ["/memory_a/rnn/LSTM_output_0", "/memory_a/Constant_1_output_0"],
                ["/memory_a/Squeeze_output_0"],
                name="/memory_a/Squeeze",
            ),
            gemm("/actor/actor.0/Gemm", "/memory_a/Squeeze_output_0", "actor.0.weight", "actor.0.bias", "actions"),
        ]

    write(
        "recurrent.onnx",
        small_actor(rng, tweak=lstm),
        "a recurrent actor exported without its state: Unsqueeze, LSTM (hidden 8, no initial_h or initial_c "
        "input, no Y_h or Y_c output), Squeeze, Gemm: its state would start from zero at every step",
        "node '/memory_a/rnn/LSTM', op LSTM, that it has no initial_h",
    )

    write(
        "dynamic_dim.onnx",
        small_actor(rng, in_dims=["batch", "n_obs"]),
        "input 'obs' has shape [batch, n_obs]: its width is symbolic",
        "input 'obs', dimension 1 'n_obs'",
    )

    def half(nodes, inits, inputs, outputs):
        i = next(k for k, t in enumerate(inits) if t.name == "actor.2.weight")
        w = numpy_helper.to_array(inits[i]).astype(np.float16)
        inits[i] = numpy_helper.from_array(w, "actor.2.weight")

    write(
        "float16.onnx",
        small_actor(rng, tweak=half),
        "the second Gemm's weight initializer 'actor.2.weight' is FLOAT16 (the rest float32; ONNX Runtime refuses it too)",
        "node '/actor/actor.2/Gemm' (Gemm), initializer 'actor.2.weight', type FLOAT16",
    )

    write(
        "elu_alpha.onnx",
        small_actor(rng, act_attrs={"alpha": 0.5}),
        "Elu with alpha 0.5 (the blob's ELU has alpha 1)",
        "node '/actor/actor.1/Elu', op Elu, alpha 0.5",
    )

    def weight_input(nodes, inits, inputs, outputs):
        i = next(k for k, t in enumerate(inits) if t.name == "actor.0.weight")
        del inits[i]
        inputs.append(io("actor.0.weight", [8, 4]))

    write(
        "weight_as_input.onnx",
        small_actor(rng, tweak=weight_input),
        "the first Gemm's B 'actor.0.weight' is a second graph input, not an initializer",
        "node '/actor/actor.0/Gemm' (Gemm), its B 'actor.0.weight' (a graph input, not an initializer)",
    )

    def trans_a(nodes, inits, inputs, outputs):
        n = node_named(nodes, "/actor/actor.2/Gemm")
        for a in n.attribute:
            if a.name == "transA":
                a.i = 1
                break
        else:
            n.attribute.append(helper.make_attribute("transA", 1))

    write(
        "gemm_transA.onnx",
        small_actor(rng, tweak=trans_a),
        "the second Gemm has transA=1 (A would be the transposed activation)",
        "node '/actor/actor.2/Gemm' (Gemm), transA=1",
        check=False,  # the node itself is valid ONNX; shapes only fail at run time
    )

    def critic(nodes, inits, inputs, outputs):
        # an actor-critic exported whole: the critic 4-8-1 reads obs too and is a second output
        for k, (w, b) in enumerate(small_layers(rng, [4, 8, 1])):
            inits += [init(f"critic.{2 * k}.weight", w), init(f"critic.{2 * k}.bias", b)]
        nodes += [
            gemm("/critic/critic.0/Gemm", "obs", "critic.0.weight", "critic.0.bias", "/critic/critic.0/Gemm_output_0"),
            helper.make_node(
                "Elu", ["/critic/critic.0/Gemm_output_0"], ["/critic/critic.1/Elu_output_0"], name="/critic/critic.1/Elu", alpha=1.0
            ),
            gemm("/critic/critic.2/Gemm", "/critic/critic.1/Elu_output_0", "critic.2.weight", "critic.2.bias", "values"),
        ]
        outputs.append(io("values", ["batch", 1]))

    write(
        "two_outputs.onnx",
        small_actor(rng, tweak=critic),
        "actor and critic exported together: graph outputs 'actions' and 'values'",
        "the graph's 2 outputs, 'actions' and 'values'",
    )

    def external(nodes, inits, inputs, outputs):
        t = next(t for t in inits if t.name == "actor.0.weight")
        n = len(t.raw_data)
        t.ClearField("raw_data")
        t.data_location = TensorProto.EXTERNAL
        for k, v in (("location", "actor.0.weight.bin"), ("offset", "0"), ("length", str(n))):
            e = t.external_data.add()
            e.key, e.value = k, v

    write(
        "external_data.onnx",
        small_actor(rng, tweak=external),
        "initializer 'actor.0.weight' has data_location EXTERNAL (file 'actor.0.weight.bin', not written): "
        "the importer must refuse without opening it",
        "initializer 'actor.0.weight' (external data)",
        check=False,  # the checker would look for the external file
    )

    def residual(nodes, inits, inputs, outputs):
        # obs -> Gemm 4-8 -> Elu (h1) -> Gemm 8-8 -> Elu (h2) -> Add(h1, h2) -> Gemm 8-2
        i = next(k for k, n in enumerate(nodes) if n.name == "/actor/actor.4/Gemm")
        add = helper.make_node(
            "Add",
            ["/actor/actor.1/Elu_output_0", "/actor/actor.3/Elu_output_0"],
            ["/actor/residual/Add_output_0"],
            name="/actor/residual/Add",
        )
        nodes[i].input[0] = "/actor/residual/Add_output_0"
        nodes.insert(i, add)

    write(
        "branching.onnx",
        small_actor(rng, widths=(4, 8, 8, 2), tweak=residual),
        "a residual: the output of '/actor/actor.1/Elu' feeds '/actor/actor.2/Gemm' and the Add "
        "'/actor/residual/Add' (whose other operand is '/actor/actor.3/Elu')",
        "node '/actor/actor.1/Elu' (output used by 2 nodes), or the Add '/actor/residual/Add' of two activations",
    )

    def mismatch(nodes, inits, inputs, outputs):
        i = next(k for k, t in enumerate(inits) if t.name == "actor.2.weight")
        inits[i] = init("actor.2.weight", rng.normal(0.0, 0.5, (2, 6)))

    write(
        "shape_mismatch.onnx",
        small_actor(rng, tweak=mismatch),
        "the second Gemm's weight is [2][6] but the layer before it is 8 wide",
        "node '/actor/actor.2/Gemm' (Gemm): weight width 6 vs 8",
        check=False,  # full shape inference would reject it, the structural checker does not look
    )

    # Recurrent actors with their state miswired (mapping bad/recurrent.yaml: h_in -> h_out, c_in -> c_out).
    write_recurrent_mapping(os.path.join(bad, "recurrent.yaml"), flat, "LSTM",
                            ["the recurrent models in bad/: 45 observations, 12 actions, an LSTM's h and c"])
    n_in, n_out = len(flat["observation_names"]), len(flat["action_names"])

    def small_lstm(hidden=8, tweak=None, declared=None):
        g = recurrent_graph("LSTM", n_in, 1, hidden, [(rng.normal(0.0, 0.3, (n_out, hidden)), np.zeros(n_out))], rng)
        if declared:  # the state ports declared with another hidden size
            for v in list(g.input) + list(g.output):
                if v.name in ("h_in", "c_in", "h_out", "c_out"):
                    v.type.tensor_type.shape.dim[2].dim_value = declared
        if tweak:
            tweak(g)
        return g

    def rnn(g):
        return next(n for n in g.node if n.op_type in ("LSTM", "GRU"))

    def not_wired(g):
        # the node's Y_h goes nowhere; 'h_out' is the Identity of 'h_in' (the state never changes)
        rnn(g).output[1] = "/memory_a/rnn/LSTM_output_1"
        g.node.append(helper.make_node("Identity", ["h_in"], ["h_out"], name="/memory_a/Identity"))

    write(
        "lstm_state_not_wired.onnx",
        small_lstm(tweak=not_wired),
        "the LSTM's Y_h reaches no graph output; the graph output 'h_out' is an Identity of 'h_in'",
        "node '/memory_a/rnn/LSTM', its Y_h, not wired back",
    )

    def swapped(g):
        n = rnn(g)
        n.output[1], n.output[2] = "c_out", "h_out"

    write(
        "lstm_state_swapped.onnx",
        small_lstm(tweak=swapped),
        "Y_h is written to 'c_out' and Y_c to 'h_out': the next h would be read as c",
        "node '/memory_a/rnn/LSTM', initial_h read from 'h_in' but written to 'c_out'",
    )

    write(
        "lstm_hidden_mismatch.onnx",
        small_lstm(hidden=8, declared=16),
        "hidden_size 8, but the state inputs and outputs are declared [1, batch, 16]",
        "node '/memory_a/rnn/LSTM', state 'h_in' of size 16, hidden_size 8",
        check=False,  # shape inference would reject it
    )

    def bidirectional(g):
        n = rnn(g)
        n.attribute.append(helper.make_attribute("direction", "bidirectional"))

    write(
        "lstm_bidirectional.onnx",
        small_lstm(tweak=bidirectional),
        "direction 'bidirectional' (its weights are those of one direction)",
        "node '/memory_a/rnn/LSTM', direction 'bidirectional'",
        check=False,
    )

    def peephole(g):
        n = rnn(g)
        g.initializer.append(init("onnx::LSTM_P", rng.normal(0.0, 0.1, (1, 3 * 8))))
        n.input.append("onnx::LSTM_P")

    write(
        "lstm_peephole.onnx",
        small_lstm(tweak=peephole),
        "an LSTM with peepholes (input P)",
        "node '/memory_a/rnn/LSTM', peepholes",
    )

    with open(os.path.join(bad, "README"), "w") as f:
        f.write("# ONNX models `pbppo import-onnx` must refuse\n\n")
        f.write("Written by tools/onnx/make_models.py (fixed seeds). Apart from the two that are not protobuf at all,\n")
        f.write("each is a small actor (4-8-2 Gemm + Elu with torch's node names unless the table says otherwise)\n")
        f.write("with one thing wrong. The last column is what the importer's error must name.\n\n")
        f.write("| file | what is wrong | the error names |\n| --- | --- | --- |\n")
        for name, wrong, must in rows:
            f.write(f"| `{name}` | {wrong} | {must} |\n")
    return rows


# --------------------------------------------------------------------------------------- main


def read_layout_actions(path):
    """The action entries of a robot's io_layout.yaml (flow maps only; no YAML library needed)."""
    acts, in_actions = {}, False
    with open(path) as f:
        for line in f:
            s = line.strip()
            if s.startswith("actions:"):
                in_actions = True
                continue
            if in_actions and s.startswith("- {") and s.endswith("}"):
                entry = {}
                for part in s[3:-1].split(","):
                    k, v = (t.strip() for t in part.split(":", 1))
                    try:
                        entry[k] = float(v)
                    except ValueError:
                        entry[k] = v.strip('"')
                acts[entry["name"]] = entry
    return acts


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--flat-json", required=True, help="pbppo inspect --json --weights of flat.blob")
    ap.add_argument("--auv-json", required=True, help="pbppo inspect --json --weights of auv_nav.blob")
    ap.add_argument(
        "--auv-layout",
        default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "models", "auv", "io_layout.yaml"),
        help="the AUV's io_layout.yaml (default: the repository's)",
    )
    a = ap.parse_args()
    os.makedirs(a.out_dir, exist_ok=True)

    flat, flat_layers = load_blob_json(a.flat_json, "flat")
    auv, auv_layers = load_blob_json(a.auv_json, "auv_nav")
    rsl_rl_walk(a.out_dir, flat, flat_layers)
    normalised_walk(a.out_dir, flat, flat_layers)
    sb3_auv(a.out_dir, auv, auv_layers, read_layout_actions(a.auv_layout))
    small = leaky_tanh_head(a.out_dir)
    stacked_history(a.out_dir, "history_frame_major", "frame-major", oldest_first=False)
    stacked_history(a.out_dir, "history_term_major", "term-major", oldest_first=True)
    recurrent_models(a.out_dir, flat, flat_layers)
    quad_layout = os.path.join(os.path.dirname(a.auv_layout), "..", "quadruped", "io_layout.yaml")
    unitree_walk(a.out_dir, flat, flat_layers, read_layout_actions(quad_layout))
    bad_models(a.out_dir, small, flat)
    for root, _, files in sorted(os.walk(a.out_dir)):
        for fn in sorted(files):
            p = os.path.join(root, fn)
            print(f"  {os.path.relpath(p, a.out_dir):<28} {os.path.getsize(p):>9} bytes")


if __name__ == "__main__":
    main()
