#!/usr/bin/python3
"""An independent oracle for the Unitree Go2's message CRC (LowCmd_.crc, LowState_.crc), written
from the algorithm's definition, not from the controller's C++ and not from Unitree's code.

The CRC is CRC-32/MPEG-2 (polynomial 0x04C11DB7, initial value 0xFFFFFFFF, no input or output
reflection, no final XOR) over the message packed as a little-endian C struct with natural
alignment (every primitive at a multiple of its size, every struct padded to its largest member's
alignment, padding bytes zero), read as 32-bit little-endian words, every word but the last (the
`crc` member itself), each word fed most significant bit first.

The member list comes from the robot's IDL files (models/go2/idl/*.idl), read here by a small
parser of the subset they use (modules, structs, primitive members, nested structs, fixed arrays,
#include "file" beside the including file). The packed struct is built with Python's struct module.

usage:
  crc_oracle.py --idl-dir models/go2/idl --type LowState_ --seed N [--out FILE.json]
      fills a message from the seed (one deterministic pseudo-random value per leaf, splitmix64),
      sets its crc, and writes {"type", "c_size", "members": {leaf path: value}, "packed_hex", "crc"}
  crc_oracle.py --check FILE.bin [--idl-dir DIR --type T]
      prints the CRC of a packed C struct file (and whether its last word holds it); with --type
      the file's size is checked against the struct's
  crc_oracle.py --idl-dir DIR --type T --layout
      prints each leaf's path, type and C offset (to compare with another reader)
  crc_oracle.py --self-test
The self-test always runs first; a failure exits 1.
"""
import argparse
import json
import os
import re
import struct
import sys

POLY = 0x04C11DB7


def crc32_mpeg2_bytes(data, crc=0xFFFFFFFF):
    """CRC-32/MPEG-2 of `data` (bytes), each byte fed most significant bit first."""
    for byte in data:
        crc ^= byte << 24
        for _ in range(8):
            crc = ((crc << 1) ^ POLY) & 0xFFFFFFFF if crc & 0x80000000 else (crc << 1) & 0xFFFFFFFF
    return crc


def crc32_mpeg2_words(words, crc=0xFFFFFFFF):
    """The same register fed 32-bit words, each most significant bit first.

    An MSB-first CRC processes a bit stream; feeding a 32-bit word from bit 31 down to bit 0 is
    the same bit stream as feeding its four bytes in big-endian order (byte 3 first), each byte MSB
    first. So the word-wise CRC of words w0, w1, ... equals the byte-wise CRC-32/MPEG-2 of
    w0.to_bytes(4, "big") + w1.to_bytes(4, "big") + ...; since the words are read little-endian
    from the packed struct, that is the byte-wise CRC of the struct with every 4-byte group
    reversed. The check value 0x0376E6E7 of "123456789" (byte-wise) pins the register itself; the
    self-test also checks the word/byte equivalence.
    """
    for word in words:
        crc ^= word & 0xFFFFFFFF
        for _ in range(32):
            crc = ((crc << 1) ^ POLY) & 0xFFFFFFFF if crc & 0x80000000 else (crc << 1) & 0xFFFFFFFF
    return crc


def go2_crc(packed):
    """The Go2's CRC of a packed C struct (bytes, a multiple of 4): every word but the last."""
    if len(packed) % 4 != 0 or len(packed) < 4:
        raise ValueError(f"a packed message of {len(packed)} bytes is not whole 32-bit words")
    n = len(packed) // 4 - 1
    return crc32_mpeg2_words(struct.unpack(f"<{n}I", packed[: 4 * n]))


def self_test():
    failures = []
    got = crc32_mpeg2_bytes(b"123456789")
    if got != 0x0376E6E7:
        failures.append(f'CRC-32/MPEG-2("123456789") = 0x{got:08X}, the check value is 0x0376E6E7')
    data = b"12345678ABCDEFGH\x00\xff\x10\x80"
    words = struct.unpack(f"<{len(data) // 4}I", data)
    swapped = b"".join(w.to_bytes(4, "big") for w in words)
    if crc32_mpeg2_words(words) != crc32_mpeg2_bytes(swapped):
        failures.append("word-wise MSB-first != byte-wise over big-endian words")
    big_words = struct.unpack(f">{len(data) // 4}I", data)
    if crc32_mpeg2_words(big_words) != crc32_mpeg2_bytes(data):
        failures.append("word-wise over big-endian reads != byte-wise")
    if crc32_mpeg2_words([]) != 0xFFFFFFFF:
        failures.append("the CRC of nothing is not the initial value")
    return failures


# --- The IDL subset --------------------------------------------------------------------------

# IDL primitive -> (struct format character, size, kind)
PRIMITIVES = {
    "boolean": ("B", 1, "bool"),
    "char": ("b", 1, "int"),
    "octet": ("B", 1, "uint"),
    "int8": ("b", 1, "int"),
    "uint8": ("B", 1, "uint"),
    "short": ("h", 2, "int"),
    "int16": ("h", 2, "int"),
    "unsigned short": ("H", 2, "uint"),
    "uint16": ("H", 2, "uint"),
    "long": ("i", 4, "int"),
    "int32": ("i", 4, "int"),
    "unsigned long": ("I", 4, "uint"),
    "uint32": ("I", 4, "uint"),
    "long long": ("q", 8, "int"),
    "int64": ("q", 8, "int"),
    "unsigned long long": ("Q", 8, "uint"),
    "uint64": ("Q", 8, "uint"),
    "float": ("f", 4, "float"),
    "double": ("d", 8, "float"),
}

TOKEN = re.compile(r"\s*(::|[A-Za-z_][A-Za-z0-9_]*|\d+|[{}\[\];,<>:=])")


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


class IdlReader:
    """Structs by qualified name ("unitree_go::msg::dds_::LowCmd_"), each a list of members
    (name, type, dims) with type a primitive name or a qualified struct name."""

    def __init__(self):
        self.structs = {}
        self.seen_files = set()

    def read_file(self, path):
        path = os.path.normpath(path)
        if path in self.seen_files:
            return
        self.seen_files.add(path)
        with open(path, encoding="utf-8") as f:
            text = strip_comments(f.read())
        body = []
        for line in text.splitlines():
            s = line.strip()
            if s.startswith("#"):
                m = re.match(r'#\s*include\s*[<"]([^">]+)[">]', s)
                if m:
                    self.read_file(os.path.join(os.path.dirname(path), m.group(1)))
                continue
            body.append(line)
        self._parse(" ".join(body), path)

    def _parse(self, text, path):
        toks = []
        pos = 0
        text = text.rstrip()
        while pos < len(text):
            m = TOKEN.match(text, pos)
            if not m:
                raise SystemExit(f"{path}: cannot read IDL near {text[pos:pos + 40]!r}")
            toks.append(m.group(1))
            pos = m.end()
        self._toks, self._i, self._path = toks, 0, path
        self._scope(prefix=[])

    def _next(self):
        t = self._toks[self._i]
        self._i += 1
        return t

    def _expect(self, t):
        got = self._next()
        if got != t:
            raise SystemExit(f"{self._path}: expected {t!r}, found {got!r}")

    def _scope(self, prefix):
        while self._i < len(self._toks):
            t = self._next()
            if t == "}":
                return
            if t == ";":
                continue
            if t == "module":
                name = self._next()
                self._expect("{")
                self._scope(prefix + [name])
            elif t == "struct":
                name = self._next()
                if self._toks[self._i] == ";":  # forward declaration
                    continue
                self._expect("{")
                self.structs["::".join(prefix + [name])] = self._members(prefix)
            else:
                raise SystemExit(f"{self._path}: unsupported IDL construct {t!r}")

    def _type(self, prefix):
        words = [self._next()]
        if words[0] == "unsigned":
            words.append(self._next())
            if words[-1] == "long" and self._toks[self._i] == "long":
                words.append(self._next())
        elif words[0] == "long" and self._toks[self._i] == "long":
            words.append(self._next())
        name = " ".join(words)
        if name in PRIMITIVES:
            return name
        while self._toks[self._i] == "::":
            name += self._next() + self._next()
        return self._resolve(name.lstrip(":"), prefix)

    def _resolve(self, name, prefix):
        for k in range(len(prefix), -1, -1):
            q = "::".join(prefix[:k] + [name])
            if q in self.structs:
                return q
        raise SystemExit(f"{self._path}: unknown type {name!r}")

    def _members(self, prefix):
        members = []
        while True:
            if self._toks[self._i] == "}":
                self._i += 1
                return members
            typ = self._type(prefix)
            while True:
                name = self._next()
                dims = []
                while self._toks[self._i] == "[":
                    self._i += 1
                    dims.append(int(self._next()))
                    self._expect("]")
                members.append((name, typ, dims))
                sep = self._next()
                if sep == ";":
                    break
                if sep != ",":
                    raise SystemExit(f"{self._path}: expected ',' or ';' after member {name!r}")

    def find(self, type_name):
        t = type_name.lstrip(":")
        if t in self.structs:
            return t
        hits = [q for q in self.structs if q.split("::")[-1] == t]
        if len(hits) != 1:
            raise SystemExit(f"type {type_name!r}: {'ambiguous' if hits else 'not found'}")
        return hits[0]


def read_idl_dir(idl_dir):
    reader = IdlReader()
    for name in sorted(os.listdir(idl_dir)):
        if name.endswith(".idl"):
            reader.read_file(os.path.join(idl_dir, name))
    return reader


# --- The packed C struct ---------------------------------------------------------------------


def align_of(reader, typ):
    if typ in PRIMITIVES:
        return PRIMITIVES[typ][1]
    return max(align_of(reader, t) for _, t, _ in reader.structs[typ])


def flatten(reader, typ, path="", base=0):
    """(leaves, size): leaves as (path, primitive, c_offset) in declaration order; the struct's C
    layout with natural alignment, its size padded to its alignment."""
    leaves = []
    offset = 0
    for name, mtype, dims in reader.structs[typ]:
        a = align_of(reader, mtype)
        offset = (offset + a - 1) // a * a
        if mtype in PRIMITIVES:
            esize = PRIMITIVES[mtype][1]
        else:
            esize = flatten(reader, mtype)[1]
        count = 1
        for d in dims:
            count *= d
        for k in range(count):
            index = ""
            rest = k
            for d in reversed(dims):
                index = f"[{rest % d}]" + index
                rest //= d
            p = f"{path}{name}{index}"
            at = base + offset + k * esize
            if mtype in PRIMITIVES:
                leaves.append((p, mtype, at))
            else:
                leaves.extend(flatten(reader, mtype, p + ".", at)[0])
        offset += count * esize
    a = align_of(reader, typ)
    return leaves, (offset + a - 1) // a * a


def pack(leaves, size, values):
    """The packed little-endian C struct: each leaf at its offset, padding zero."""
    buf = bytearray(size)
    for path, typ, at in leaves:
        fmt = "<" + PRIMITIVES[typ][0]
        struct.pack_into(fmt, buf, at, values[path])
    return bytes(buf)


class SplitMix64:
    def __init__(self, seed):
        self.state = seed & 0xFFFFFFFFFFFFFFFF

    def next(self):
        self.state = (self.state + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        return z ^ (z >> 31)


def fill(leaves, seed):
    """One value per leaf, in leaf order: integers over their type's whole range, floats in
    [-100, 100) rounded to the leaf's precision, booleans 0/1."""
    rng = SplitMix64(seed)
    values = {}
    for path, typ, _ in leaves:
        fmt, size, kind = PRIMITIVES[typ]
        r = rng.next()
        if kind == "bool":
            v = r & 1
        elif kind == "uint":
            v = r & ((1 << (8 * size)) - 1)
        elif kind == "int":
            v = r & ((1 << (8 * size)) - 1)
            if v >= 1 << (8 * size - 1):
                v -= 1 << (8 * size)
        else:
            v = (r >> 11) / float(1 << 53) * 200.0 - 100.0
            v = struct.unpack("<" + fmt, struct.pack("<" + fmt, v))[0]
        values[path] = v
    return values


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--idl-dir")
    ap.add_argument("--type")
    ap.add_argument("--seed", type=int)
    ap.add_argument("--out")
    ap.add_argument("--check")
    ap.add_argument("--layout", action="store_true")
    ap.add_argument("--self-test", action="store_true")
    args = ap.parse_args()

    failures = self_test()
    if failures:
        for f in failures:
            print(f"self-test: {f}", file=sys.stderr)
        return 1
    if args.self_test:
        print('self-test ok: CRC-32/MPEG-2("123456789") = 0x0376E6E7, word-wise == byte-wise big-endian')
        if not (args.check or args.type):
            return 0

    layout = None
    if args.type:
        if not args.idl_dir:
            ap.error("--type needs --idl-dir")
        reader = read_idl_dir(args.idl_dir)
        qualified = reader.find(args.type)
        leaves, size = flatten(reader, qualified)
        layout = (qualified, leaves, size)
        if leaves[-1][0] != "crc" or leaves[-1][2] != size - 4:
            print(f"{qualified}: its last member is not a 32-bit crc in the struct's last word", file=sys.stderr)
            return 1

    if args.check:
        with open(args.check, "rb") as f:
            packed = f.read()
        if layout and len(packed) != layout[2]:
            print(f"{args.check}: {len(packed)} bytes, {layout[0]} packs to {layout[2]}", file=sys.stderr)
            return 1
        crc = go2_crc(packed)
        stored = struct.unpack_from("<I", packed, len(packed) - 4)[0]
        print(f"crc 0x{crc:08x} stored 0x{stored:08x} {'match' if crc == stored else 'MISMATCH'}")
        return 0

    if layout is None:
        ap.error("give --type with --idl-dir (with --seed or --layout), or --check FILE.bin")
    qualified, leaves, size = layout
    if args.layout:
        for path, typ, at in leaves:
            print(f"{path} {typ} {at}")
        print(f"c_size {size}")
        return 0
    if args.seed is None:
        ap.error("--seed N is needed to fill a message")
    values = fill(leaves, args.seed)
    values["crc"] = 0
    crc = go2_crc(pack(leaves, size, values))
    values["crc"] = crc
    packed = pack(leaves, size, values)
    if go2_crc(packed) != crc:
        raise AssertionError("the crc member is inside the words the CRC covers")
    doc = {
        "type": qualified,
        "seed": args.seed,
        "c_size": size,
        "members": {path: values[path] for path, _, _ in leaves},
        "packed_hex": packed.hex(),
        "crc": f"0x{crc:08x}",
    }
    text = json.dumps(doc, indent=1) + "\n"
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            f.write(text)
        print(f"{qualified} seed {args.seed}: c_size {size} crc 0x{crc:08x} -> {args.out}")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
