#!/usr/bin/env python3
"""Import circles between the source files of one crate, and files that are too long.

Usage: tools/relayer/cycles.py [REPO_ROOT] [--crate NAME]... [--edges] [--no-reexports] [--max-lines N]

For every crate under `crates/*/src` (each of `lib.rs`, `main.rs` and `bin/*.rs` is a root of
its own module tree), this builds the graph "file A imports file B" between the crate's own
source files and prints every strongly connected component of more than one file (an "import
circle"), then their count. It exits 1 if there is any.

An edge A -> B is a path written in A that names an item or module of file B:
  * `use crate::a::b::X`, `use super::X`, `use self::x::Y`, `use child::Z` (a module declared
    with `mod child;` in the same module), with `{...}` trees expanded;
  * paths in code: `crate::a::f(..)`, `super::T`, `self::m::T`, `child::f(..)`, and paths that
    start with a module brought into scope by a `use` (`use crate::riemann; riemann::mean(..)`).
A module `a` lives in `a.rs` or `a/mod.rs`; a path into a submodule is an edge to the
submodule's file. Re-exports are followed to the file that defines the item (so an alias
module such as `pub use classifiers::svm;` at the crate root does not hide where `crate::svm::X`
lives), and the re-exporting file itself gets an edge to the file it re-exports from (`pub use
child::X;`, `pub use child::*;`). Importing a module by name alone (`use crate::a;`) is no edge;
using it (`a::f()`) is. `#[cfg(test)]` items (e.g. `mod tests { .. }`, `mod tests;`) and
`tests/` folders are ignored; comments and string literals are skipped. Paths into other
crates are not edges. A `mod NAME` written in a macro invocation (e.g. oddball-decode's
`registry! { Lda(..), mod lda, ..; }`, which expands to `pub mod lda;`) declares the module
`NAME` of the file beside it, as `mod NAME;` would.

It also prints, per crate, the files longer than `--max-lines` (1000) lines before their first
`#[cfg(test)]` line.
"""

import argparse
import os
import re
import sys
from collections import defaultdict

ITEM_KEYWORDS = {
    "fn", "struct", "enum", "trait", "type", "const", "static", "union", "mod",
}


# ---------------------------------------------------------------- lexing


def tokens(src):
    """Identifiers, `::`, and single punctuation characters; comments, strings, chars and
    numbers are dropped (a string becomes the token '"', a number the token '0')."""
    out = []
    i, n = 0, len(src)
    while i < n:
        c = src[i]
        if c.isspace():
            i += 1
        elif src.startswith("//", i):
            j = src.find("\n", i)
            i = n if j < 0 else j
        elif src.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if src.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif src.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == '"' or (c in "bc" and src.startswith('"', i + 1)):
            i = src.index('"', i) + 1
            while i < n and src[i] != '"':
                i += 2 if src[i] == "\\" else 1
            i += 1
            out.append('"')
        elif (c == "r" or (c in "bc" and i + 1 < n and src[i + 1] == "r")) and re.match(
            r'(b|c)?r#*"', src[i:i + 260]
        ):
            m = re.match(r'(b|c)?r(#*)"', src[i:])
            end = '"' + m.group(2)
            i = src.index(end, i + m.end()) + len(end)
            out.append('"')
        elif c == "'" or (c == "b" and src.startswith("'", i + 1)):
            j = i + (2 if c == "b" else 1)
            m = re.match(r"(\\(x[0-9a-fA-F]{2}|u\{[0-9a-fA-F]+\}|.)|[^\\'\n])'", src[j:j + 16])
            if m:  # a char literal
                i = j + m.end()
                out.append('"')
            else:  # a lifetime or label
                m = re.match(r"[A-Za-z_][A-Za-z0-9_]*", src[j:])
                i = j + (m.end() if m else 0)
                out.append("'")
        elif c.isalpha() or c == "_" or ord(c) > 127:
            m = re.match(r"(r#)?[^\W\d]\w*", src[i:])
            word = m.group(0)
            if word.startswith("r#"):
                word = word[2:]
            out.append(word)
            i += m.end()
        elif c.isdigit():
            m = re.match(r"[0-9][0-9a-zA-Z_]*(\.[0-9][0-9a-zA-Z_]*)?", src[i:])
            i += m.end()
            out.append("0")
        elif src.startswith("::", i):
            out.append("::")
            i += 2
        else:
            out.append(c)
            i += 1
    return out


def is_ident(tok):
    return tok[0].isalpha() or tok[0] == "_" or ord(tok[0]) > 127


OPEN, CLOSE = "([{", ")]}"


def skip_item(toks, i):
    """Index just past the item starting at toks[i] (used to drop `#[cfg(test)]` items)."""
    keyworded = toks[i] in ITEM_KEYWORDS | {
        "pub", "use", "impl", "let", "unsafe", "async", "extern", "macro_rules", "#",
    }
    depth = 0
    while i < len(toks):
        t = toks[i]
        if t in OPEN:
            depth += 1
        elif t in CLOSE:
            if depth == 0:
                return i  # closes the enclosing block: the item ended before it
            depth -= 1
            if depth == 0 and t == "}":
                return i + 1
        elif depth == 0 and (t == ";" or (t == "," and not keyworded)):
            return i + 1
        i += 1
    return i


def closing(toks, k):
    """Index of the bracket that closes the one opened at toks[k] (len(toks) if none does)."""
    depth = 0
    while k < len(toks):
        if toks[k] in OPEN:
            depth += 1
        elif toks[k] in CLOSE:
            depth -= 1
            if depth == 0:
                break
        k += 1
    return k


def attribute(toks, i):
    """(text, index after) of the attribute `#[...]` / `#![...]` at toks[i]."""
    j = i + 1
    if toks[j] == "!":
        j += 1
    k = closing(toks, j)
    return " ".join(toks[j + 1:k]), k + 1


def macro_bodies(toks):
    """For each token, whether it lies inside the brackets of a macro invocation `name!(..)`,
    `name![..]` or `name! {..}` (not a `macro_rules!` definition)."""
    inside = [False] * len(toks)
    i = 0
    while i + 2 < len(toks):
        if (is_ident(toks[i]) and toks[i] != "macro_rules" and toks[i + 1] == "!"
                and toks[i + 2] in OPEN):
            k = closing(toks, i + 2)
            for j in range(i + 3, k):
                inside[j] = True
            i = k + 1
            continue
        i += 1
    return inside


def is_test_cfg(attr):
    return bool(re.match(r"cfg \( (all \( )?test\b", attr))


# ---------------------------------------------------------------- parsing a file


class Module:
    def __init__(self, path, file):
        self.path = path  # tuple of segments from the crate root
        self.file = file
        self.children = {}  # name -> Module
        self.child_files = {}  # name -> file (declared `mod name;`)
        self.bindings = {}  # name -> (path segments, context module path) from `use`
        self.globs = []  # (path segments, context) of `use path::*`
        self.defined = set()


def parse_use_tree(toks, i, prefix, out):
    """Parse a use tree at toks[i]; append (segments, binding name or '*') to out."""
    segs = list(prefix)
    while i < len(toks):
        t = toks[i]
        if t == "{":
            i += 1
            while toks[i] != "}":
                i = parse_use_tree(toks, i, segs, out)
                if toks[i] == ",":
                    i += 1
            return i + 1
        if t == "*":
            out.append((segs, "*"))
            return i + 1
        if t == "::":
            i += 1
            continue
        if is_ident(t):
            segs.append(t)
            i += 1
            if i < len(toks) and toks[i] == "as":
                out.append((segs, toks[i + 1]))
                return i + 2
            if i < len(toks) and toks[i] == "::":
                continue
            name = segs[-1]
            if name == "self":
                segs = segs[:-1]
                name = segs[-1] if segs else "self"
            out.append((segs, name))
            return i
        return i + 1
    return i


def parse_file(crate, file, modpath, occurrences, used):
    """Record the modules, uses and definitions of one file in `crate` (a dict modpath ->
    Module), append the paths it writes to `occurrences` as (file, context, segments, kind,
    name bound by a `use` or None) and the identifiers it writes outside `use` to
    `used[file]`."""
    with open(file, encoding="utf-8") as f:
        toks = tokens(f.read())
    mod = crate.setdefault(modpath, Module(modpath, file))
    mod.file = file
    used_here = used.setdefault(file, set())
    in_macro = macro_bodies(toks)
    stack = [(modpath, None)]  # (module path, brace depth at which its inline block closes)
    depth = 0
    pending_attrs = []
    i = 0
    while i < len(toks):
        t = toks[i]
        ctx = stack[-1][0]
        cur = crate[ctx]
        if t == "#" and i + 1 < len(toks) and toks[i + 1] in ("[", "!"):
            text, j = attribute(toks, i)
            if toks[i + 1] == "!" and is_test_cfg(text):
                return
            pending_attrs.append(text)
            i = j
            continue
        attrs, pending_attrs = pending_attrs, []
        if any(is_test_cfg(a) for a in attrs):
            i = skip_item(toks, i)
            continue
        if is_ident(t):
            used_here.add(t)
        if t == "{":
            depth += 1
        elif t == "}":
            depth -= 1
            if stack[-1][1] == depth:
                stack.pop()
        elif t == "mod" and i + 2 < len(toks) and is_ident(toks[i + 1]) and (i == 0 or toks[i - 1] != "::"):
            name = toks[i + 1]
            if toks[i + 2] == ";" or (in_macro[i] and toks[i + 2] != "{"):
                child_path = None
                for a in attrs:
                    m = re.match(r'path = "', a)
                    if m:
                        raise SystemExit(f"{file}: #[path] is not supported")
                cur.child_files[name] = child_path
                cur.defined.add(name)
                i += 3
                continue
            if toks[i + 2] == "{":
                sub = ctx + (name,)
                crate.setdefault(sub, Module(sub, file)).file = file
                cur.children[name] = crate[sub]
                cur.defined.add(name)
                stack.append((sub, depth))
                depth += 1
                i += 3
                continue
        elif t == "use" and (i == 0 or toks[i - 1] != "::"):
            out = []
            j = parse_use_tree(toks, i + 1, [], out)
            public = i > 0 and (toks[i - 1] == "pub" or (toks[i - 1] == ")" and i > 3 and toks[i - 4] == "pub"))
            for segs, name in out:
                if not segs:
                    continue
                if name == "*":
                    cur.globs.append((segs, ctx))
                else:
                    if name != "_":
                        cur.bindings[name] = (segs, ctx)
                kind = "use-glob" if name == "*" else "use"
                occurrences.append((file, ctx, segs, "pub-" + kind if public else kind, name))
            i = j
            continue
        elif t in ITEM_KEYWORDS and i + 1 < len(toks) and is_ident(toks[i + 1]):
            if t != "mod" and (i == 0 or toks[i - 1] not in ("::", ".")):
                cur.defined.add(toks[i + 1])
        elif t == "macro_rules" and i + 2 < len(toks) and toks[i + 1] == "!":
            cur.defined.add(toks[i + 2])
        elif is_ident(t) and i + 2 < len(toks) and toks[i + 1] == "::" and (
            i == 0 or toks[i - 1] not in ("::", "$", ".")
        ):
            segs = [t]
            j = i + 1
            while j + 1 < len(toks) and toks[j] == "::" and is_ident(toks[j + 1]):
                segs.append(toks[j + 1])
                j += 2
            used_here.update(segs)
            occurrences.append((file, ctx, segs, "code", None))
            i = j
            continue
        i += 1


def module_file(dirpath, name):
    for cand in (os.path.join(dirpath, name + ".rs"), os.path.join(dirpath, name, "mod.rs")):
        if os.path.isfile(cand):
            return cand
    return None


def load_tree(root_file):
    """All modules reachable from a crate root file, and the paths written in them."""
    crate, occurrences, used = {}, [], {}
    todo = [((), root_file)]
    while todo:
        modpath, file = todo.pop()
        if "tests" in file.split(os.sep)[:-1]:
            continue
        parse_file(crate, file, modpath, occurrences, used)
        # files of the `mod x;` declared in this file (top level or in an inline module)
        stem = os.path.basename(file)[:-3]
        base = os.path.dirname(file)
        if file != root_file and stem not in ("mod", "lib", "main"):
            base = os.path.join(base, stem)
        for mp, mod in list(crate.items()):
            if mod.file != file or mp[: len(modpath)] != modpath:
                continue
            mod_base = os.path.join(base, *mp[len(modpath):])
            for cname, state in list(mod.child_files.items()):
                if state == "loaded":
                    continue
                mod.child_files[cname] = "loaded"
                cf = module_file(mod_base, cname)
                if cf is None:
                    print(f"warning: {file}: no file for `mod {cname};`", file=sys.stderr)
                    continue
                sub = mp + (cname,)
                crate[sub] = Module(sub, cf)
                mod.children[cname] = crate[sub]
                todo.append((sub, cf))
    return crate, occurrences, used


# ---------------------------------------------------------------- resolving paths


class Resolver:
    def __init__(self, crate):
        self.crate = crate

    def start(self, ctx, segs, in_use):
        """(module path to walk from, remaining segments) or None for other crates."""
        first = segs[0]
        if first == "crate":
            return (), segs[1:]
        if first == "self":
            return ctx, segs[1:]
        if first == "super":
            mp = ctx
            k = 0
            while k < len(segs) and segs[k] == "super":
                mp = mp[:-1]
                k += 1
            return mp, segs[k:]
        mod = self.crate[ctx]
        if first in mod.children:
            return ctx, segs
        if first in mod.bindings:
            return ctx, segs
        return None

    def walk(self, mp, segs, strict=False, seen=None):
        """('module', path) or ('item', file) or None (strict: not found here)."""
        seen = set() if seen is None else seen
        mod = self.crate.get(mp)
        if mod is None:
            return None
        if not segs:
            return ("module", mp)
        name, rest = segs[0], segs[1:]
        key = (mp, name)
        if key in seen:
            return None
        seen = seen | {key}
        if name in mod.children:
            return self.walk(mod.children[name].path, rest, False, seen)
        if name in mod.bindings:
            bsegs, bctx = mod.bindings[name]
            st = self.start(bctx, bsegs, True)
            if st is None:
                return None  # another crate
            r = self.walk(st[0], st[1], False, seen)
            if r is not None and r[0] == "module" and rest:
                return self.walk(r[1], rest, False, seen)
            return r
        if name in mod.defined:
            return ("item", mod.file)
        for gsegs, gctx in mod.globs:
            st = self.start(gctx, gsegs, True)
            if st is None:
                continue
            g = self.walk(st[0], st[1], False, seen)
            if g is None or g[0] != "module":
                continue
            r = self.walk(g[1], segs, True, seen)
            if r is not None:
                return r
        if strict:
            return None
        return ("item", mod.file)


def edges_of(crate, occurrences, used, reexports=True):
    """Edges file -> files it imports. Without `reexports`, a `pub use` is an edge only when
    the file itself uses the name it binds (a facade `mod.rs` re-exporting a child is no edge)."""
    res = Resolver(crate)
    edges = defaultdict(set)  # file -> {file}
    why = {}
    for file, ctx, segs, kind, name in occurrences:
        public = kind.startswith("pub-")
        kind = kind[4:] if public else kind
        if public and not reexports and (kind == "use-glob" or name not in used.get(file, ())):
            continue
        st = res.start(ctx, segs, kind != "code")
        if st is None:
            continue
        if kind == "code" and segs[0] not in ("crate", "self", "super"):
            # a path starting with a name in scope: only modules start a path of interest
            r0 = res.walk(ctx, segs[:1])
            if r0 is None or r0[0] != "module":
                continue
        r = res.walk(st[0], st[1])
        if r is None:
            continue
        if r[0] == "module":
            if kind != "use-glob":
                continue
            target = crate[r[1]].file
        else:
            target = r[1]
        if target != file:
            edges[file].add(target)
            why.setdefault((file, target), ("pub use " if public else "use " if kind != "code" else "")
                           + "::".join(segs) + ("::*" if kind == "use-glob" else ""))
    return edges, why


def sccs(nodes, edges):
    """Tarjan's strongly connected components."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        work = [(v, iter(sorted(edges.get(v, ()))))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        while work:
            node, it = work[-1]
            advanced = False
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
                    advanced = True
                    break
                if w in on:
                    low[node] = min(low[node], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                out.append(comp)

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


def lines_before_tests(file):
    n = 0
    with open(file, encoding="utf-8") as f:
        for line in f:
            if line.startswith("#[cfg(test)]"):
                break
            n += 1
    return n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("root", nargs="?", default=".")
    ap.add_argument("--crate", action="append", help="only this crate (folder name under crates/)")
    ap.add_argument("--edges", action="store_true", help="print every edge with one path that made it")
    ap.add_argument("--max-lines", type=int, default=1000)
    ap.add_argument("--no-reexports", action="store_true",
                    help="a `pub use` is an edge only when the file itself uses the name (shows the circles "
                    "that are not only facade mod.rs/lib.rs re-exports)")
    args = ap.parse_args()

    crates_dir = os.path.join(args.root, "crates")
    names = sorted(d for d in os.listdir(crates_dir) if os.path.isdir(os.path.join(crates_dir, d, "src")))
    if args.crate:
        names = [n for n in names if n in args.crate]
    circles = 0
    long_files = []
    for name in names:
        src = os.path.join(crates_dir, name, "src")
        roots = [os.path.join(src, r) for r in ("lib.rs", "main.rs") if os.path.isfile(os.path.join(src, r))]
        bindir = os.path.join(src, "bin")
        if os.path.isdir(bindir):
            roots += sorted(os.path.join(bindir, f) for f in os.listdir(bindir) if f.endswith(".rs"))
        seen_files = set()
        for root in roots:
            crate, occ, used = load_tree(root)
            edges, why = edges_of(crate, occ, used, not args.no_reexports)
            files = {m.file for m in crate.values()}
            seen_files |= files
            rel = lambda p: os.path.relpath(p, src)
            if args.edges:
                for a in sorted(edges):
                    for b in sorted(edges[a]):
                        print(f"{name}: {rel(a)} -> {rel(b)}   ({why[(a, b)]})")
            for comp in sccs(files, edges):
                if len(comp) < 2:
                    continue
                circles += 1
                members = sorted(comp)
                print(f"import circle in {name} ({rel(root)}): {len(comp)} files")
                inside = set(comp)
                for a in members:
                    for b in sorted(edges[a] & inside):
                        print(f"    {rel(a)} -> {rel(b)}   ({why[(a, b)]})")
        for f in sorted(seen_files):
            n = lines_before_tests(f)
            if n > args.max_lines:
                long_files.append((name, os.path.relpath(f, args.root), n))
    print(f"{circles} import circle(s)")
    for name, f, n in long_files:
        print(f"over {args.max_lines} lines before tests: {f} ({n})")
    print(f"{len(long_files)} file(s) over {args.max_lines} lines before tests")
    return 1 if circles else 0


if __name__ == "__main__":
    sys.exit(main())
