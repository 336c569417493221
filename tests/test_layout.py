"""The layout docs/design.md describes holds: imports flow one way between the layers
(function-level imports included), no module imports itself back through a circle, no
module outgrows ~800 lines, the private protocol of the samplers stays inside them, the
constants the host and the kernels share have one source, and no file cites a document
the repository does not hold."""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "clsamp"

# docs/design.md, "Layers": a module may import its own layer and the layers before it.
LAYERS = [
    ("core", {"errors", "validation", "runtime", "host_memory", "philox", "number_theory",
              "generating_matrices", "permutation", "files", "parallel", "transforms", "density",
              "float_float"}),
    ("geometry", {"geometry"}),
    ("samplers", {"samplers"}),
    ("analysis", {"nufft", "spectral_stats", "spectrum_ff", "spectrum", "metrics"}),
    ("experiments", {"integrands", "integrand_kernel", "families", "experiments_ff", "estimates", "sweep",
                     "results", "theory", "integration", "cubature", "cubature_device", "fused"}),
    ("render", {"scene", "pixel_sampling", "render_numpy", "render"}),
    ("report", {"plot_axes", "plot_points", "plots", "report", "tour_blue", "tour_cost", "tour_qmc",
                "tour", "cli", "cli_source", "__main__", "__init__"}),
]


def _module_name(path):
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules():
    return {_module_name(p): p for p in PACKAGE.rglob("*.py")}


MODULES = _modules()


def _resolve(module, level, name):
    """The clsamp module an import names (relative or absolute), or None if outside."""
    path = MODULES[module]
    base = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    if level:
        base = base[:len(base) - (level - 1)]
        target = ".".join(base + ([name] if name else []))
    else:
        target = name or ""
    return target if target.split(".")[0] == "clsamp" else None


def _imports(module):
    """Every clsamp module ``module`` imports, anywhere in its body (functions included)."""
    tree = ast.parse(MODULES[module].read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "clsamp":
                    found.add(alias.name)
        elif isinstance(node, ast.ImportFrom):
            target = _resolve(module, node.level, node.module)
            if target is None:
                continue
            for alias in node.names:              # `from . import x` names the module x
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in MODULES else target)
    return {m for m in found if m in MODULES and m != module}


GRAPH = {m: _imports(m) for m in MODULES}


def _layer(module):
    parts = module.split(".")
    top = parts[1] if len(parts) > 1 else "__init__"
    for index, (_, members) in enumerate(LAYERS):
        if top in members:
            return index
    raise AssertionError(f"{module} is in no layer of docs/design.md")


def test_every_module_has_a_layer():
    for module in MODULES:
        _layer(module)


def test_imports_flow_one_way():
    wrong = [(m, t) for m, targets in GRAPH.items() for t in targets
             if _layer(t) > _layer(m) and not m.startswith("clsamp.__")]
    assert not wrong, wrong


def test_no_import_circles():
    state, stack, cycles = {}, [], []

    def visit(m):
        state[m] = "open"
        stack.append(m)
        for t in sorted(GRAPH[m]):
            # a package's __init__ re-exporting its submodules is the way in, not a circle
            if MODULES[t].name == "__init__.py" and m.startswith(t + "."):
                continue
            if state.get(t) == "open":
                cycles.append(stack[stack.index(t):] + [t])
            elif t not in state:
                visit(t)
        stack.pop()
        state[m] = "done"

    for m in sorted(MODULES):
        if m not in state:
            visit(m)
    assert not cycles, cycles


def test_no_module_outgrows_800_lines():
    long = {m: n for m, p in MODULES.items() if (n := len(p.read_text().splitlines())) > 800}
    assert not long, long


def test_the_private_sampler_protocol_stays_in_the_samplers():
    calls = re.compile(r"\._(device|reference|optimize|generate|make)\(")
    outside = [str(p.relative_to(ROOT)) for m, p in MODULES.items()
               if not m.startswith("clsamp.samplers") and calls.search(p.read_text())]
    for folder in ("benchmarks", "tests"):
        outside += [str(p.relative_to(ROOT)) for p in (ROOT / folder).glob("*.py")
                    if calls.search(p.read_text())]
    assert not outside, outside


@pytest.mark.parametrize("name", ["VOR_BITS", "VOR_SEGMENT", "CCVT_TOP", "CCVT_SECTORS",
                                  "CCVT_BANDS", "CCVT_META", "CCVT_NO_OWNER", "CCVT_NO_SECOND"])
def test_shared_constants_come_from_the_host(name):
    # the kernels get them as build options from their one Python source and refuse to
    # build without them
    for path in (ROOT / "kernels").iterdir():
        text = path.read_text()
        assert not re.search(rf"#define\s+{name}\b", text), (path.name, name)
    from clsamp.geometry import voronoi
    from clsamp.samplers.ccvt import pairs
    defines = {**voronoi.DEFINES, **pairs.ccvt_defines()}
    assert name in defines


def test_a_kernel_without_its_constants_does_not_build():
    from clsamp import runtime
    from clsamp.errors import BuildError
    with pytest.raises(BuildError, match="VOR_BITS"):
        runtime.program("voronoi.cl")
    from clsamp.samplers.ccvt import pairs
    wrong = {**pairs.ccvt_defines(), "CCVT_META": pairs.CCVT_META + 1}
    with pytest.raises(BuildError, match="CCVT_META"):
        runtime.program("ccvt.cl", wrong)


def test_no_file_cites_a_document_the_repository_lacks():
    cited = re.compile(r"\b([A-Za-z_][\w/.-]*\.md)\b")
    files = [p for p in ROOT.rglob("*") if p.is_file() and p.suffix in (".py", ".cl", ".h", ".md")
             and ".venv" not in p.parts and ".git" not in p.parts]
    missing = []
    for path in files:
        for name in cited.findall(path.read_text(errors="replace")):
            if not ((ROOT / name).is_file() or (path.parent / name).is_file()):
                missing.append((str(path.relative_to(ROOT)), name))
    assert not missing, missing


def test_setup_ships_every_package():
    text = (ROOT / "setup.py").read_text()
    listed = set(re.findall(r'"(clsamp(?:\.\w+)*)"', text))
    packages = {_module_name(p.parent / "__init__.py") for p in PACKAGE.rglob("__init__.py")}
    assert packages <= listed, packages - listed


def test_cited_sections_exist():
    # `docs/design.md, "Rendering"`: the document has a heading with that name
    cited = re.compile(r'(docs/[\w-]+\.md),\s+"([^"]+)"')
    files = [p for p in ROOT.rglob("*") if p.is_file() and p.suffix in (".py", ".cl", ".h")
             and ".venv" not in p.parts]
    missing = []
    for path in files:
        text = re.sub(r"\s*\n\s*(\*|#)?\s*", " ", path.read_text())    # comments wrap lines
        for doc, section in cited.findall(text):
            headings = [line.lstrip("#").strip() for line in (ROOT / doc).read_text().splitlines()
                        if line.startswith("#")]
            if section not in headings:
                missing.append((str(path.relative_to(ROOT)), doc, section))
    assert not missing, missing


def test_only_the_runtime_makes_opencl_state():
    made = re.compile(r"\bcl\.(Buffer|Kernel|Program|Context|CommandQueue)\(|create_some_context"
                      r"|enqueue_map_buffer|\.Kernel\(")
    outside = [m for m, p in MODULES.items()
               if not m.startswith("clsamp.runtime") and made.search(p.read_text())]
    assert not outside, outside


def _sampler_protocol():
    """The public names ``Sampler`` declares (facts, entry points, the renderer's protocol)
    and what its ``__init__`` sets."""
    from clsamp.samplers.base import Sampler
    return {n for n in dir(Sampler) if not n.startswith("_")} | {"d", "seed", "backend"}


# what holds a sampler, by the names the package gives it
_SAMPLER_LIKE = re.compile(r"(^|\.)(\w*sampler|probe)$|make_sampler\(|\.(factory|for_image|with_seed)\(")


def test_no_module_reads_a_sampler_attribute_the_base_does_not_declare():
    # a renderer, an experiment or a report asks a sampler only what Sampler declares:
    # no getattr with a default, no attribute of one subclass
    declared = _sampler_protocol()
    wrong = []
    for module, path in MODULES.items():
        if module.startswith("clsamp.samplers"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Load):
                owner = ast.unparse(node.value)
                if _SAMPLER_LIKE.search(owner) and node.attr not in declared:
                    wrong.append((module, node.lineno, f"{owner}.{node.attr}"))
            elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                  and node.func.id in ("getattr", "hasattr") and node.args
                  and _SAMPLER_LIKE.search(ast.unparse(node.args[0]))):
                wrong.append((module, node.lineno, ast.unparse(node)))
    assert not wrong, wrong


def test_every_public_function_class_and_method_has_a_docstring():
    missing = []

    def visit(module, body, prefix):
        for node in body:
            if (isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
                    and not node.name.startswith("_")):
                if not ast.get_docstring(node):
                    missing.append(f"{module}:{node.lineno} {prefix}{node.name}")
                if isinstance(node, ast.ClassDef):
                    visit(module, node.body, f"{prefix}{node.name}.")

    for module, path in MODULES.items():
        visit(module, ast.parse(path.read_text()).body, "")
    assert not missing, missing


def _has_section(doc, *names):
    lines = [line.strip() for line in doc.splitlines()]
    return any(a in names and len(b) >= 3 and set(b) == {"-"}
               for a, b in zip(lines, lines[1:], strict=False))


def _returns_a_value(func):
    """Whether ``func``'s own body (not a nested function's) returns a value or yields."""
    def walk(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
                continue
            if isinstance(child, (ast.Yield, ast.YieldFrom)):
                return True
            if (isinstance(child, ast.Return) and child.value is not None
                    and not (isinstance(child.value, ast.Constant) and child.value.value is None)):
                return True
            if walk(child):
                return True
        return False
    return walk(func)


def _public_functions(module, body, prefix="", in_class=False):
    """(module, qualified name, node, is a method) of every public function of ``body`` and
    every public method of its public classes, properties left out."""
    found = []
    for node in body:
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) \
                or node.name.startswith("_"):
            continue
        if isinstance(node, ast.ClassDef):
            found += _public_functions(module, node.body, f"{prefix}{node.name}.", True)
            continue
        decorators = [ast.unparse(d) for d in node.decorator_list]
        if any(d == "property" or d.endswith((".setter", ".getter", ".deleter")) for d in decorators):
            continue
        found.append((module, f"{prefix}{node.name}", node, in_class and "staticmethod" not in decorators))
    return found


def test_public_functions_have_numpydoc_sections():
    # an override may point to the documented method it overrides (":meth:`Sampler.valid_n`")
    # instead of repeating that method's sections
    functions = [f for module, path in MODULES.items()
                 for f in _public_functions(module, ast.parse(path.read_text()).body)]
    documented = {qual for _, qual, node, _ in functions
                  if _has_section(ast.get_docstring(node) or "", "Parameters")}
    wrong = []
    for module, qual, node, method in functions:
        args = node.args
        named = args.posonlyargs + args.args + args.kwonlyargs
        if method:
            named = named[1:]
        if not named:
            continue
        doc = ast.get_docstring(node) or ""
        name = qual.rsplit(".", 1)[-1]
        pointed = re.findall(rf":meth:`~?([\w.]*\.{name})`", doc)
        if "." in qual and any(".".join(p.split(".")[-2:]) in documented for p in pointed):
            continue
        if not _has_section(doc, "Parameters"):
            wrong.append(f"{module}:{node.lineno} {qual} (Parameters)")
        if _returns_a_value(node) and not _has_section(doc, "Returns", "Yields"):
            wrong.append(f"{module}:{node.lineno} {qual} (Returns)")
    assert not wrong, f"{len(wrong)}: " + "\n".join(wrong)


def test_the_layer_table_of_design_md_lists_every_module_in_its_layer():
    # docs/design.md, "Layers": each row names its modules in backticks (`runtime`,
    # `metrics/`, `geometry.torus`); every module of LAYERS is in its own row
    rows = {}
    for line in (ROOT / "docs/design.md").read_text().splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 3 and cells[1] in dict(LAYERS):
            rows[cells[1]] = {re.split(r"[./]", name)[0] for name in re.findall(r"`([\w./]+)`", cells[2])}
    assert set(rows) == set(dict(LAYERS)), set(rows) ^ set(dict(LAYERS))
    wrong = {layer: sorted(members - rows[layer]) for layer, members in LAYERS
             if members - rows[layer] - {"__main__", "__init__"}}
    assert not wrong, wrong
