# Two commands on a fresh machine with python3 and make: `make demo`, `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    := out

.PHONY: setup browser demo test test-slow fuzz mutate bench benchmarks roundtrip clean

$(STAMP): pyproject.toml planefmt/container/_chains.c planefmt/geometry/_collapse.c js/package-lock.json
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[test]'
	# Khronos glTF-Validator (npm, pinned by tools/validators/package-lock.json) for the converter tests
	if command -v npm >/dev/null; then tools/install_validators.sh; fi
	# the JavaScript reader's packages (js/package-lock.json: fflate, brotli-dec-wasm, three, playwright-core, draco3d)
	if command -v npm >/dev/null; then (cd js && npm ci --silent --no-audit --no-fund); fi
	touch $(STAMP)

setup: $(STAMP) browser

# Debian's chromium for the viewer's headless test (js/test/viewer.test.mjs skips without it), where
# node is here and root can apt-get; idempotent and quiet
browser:
	@if command -v node >/dev/null && ! command -v chromium >/dev/null && [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	  echo "installing chromium (apt-get) for the viewer's test"; \
	  export DEBIAN_FRONTEND=noninteractive; \
	  apt-get install -y -qq --no-install-recommends chromium >/dev/null 2>&1 || \
	  { apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq --no-install-recommends chromium >/dev/null 2>&1; } || \
	  echo "chromium could not be installed: the viewer's test will skip"; fi

demo: $(STAMP)
	mkdir -p $(OUT)
	$(BIN)/python -m planefmt_converters.demo $(OUT)

# -n auto: pytest-xdist, one worker per core (the suite takes about 12 minutes on one core)
# js/: the JavaScript reader's tests (conformance cases, damaged files, corpus against planefmt,
# the three.js loader, the viewer in headless Chromium), where node is installed
test: $(STAMP) browser
	$(BIN)/python -m pytest -n auto --dist worksteal
	$(BIN)/python -m conformance --level geometry
	if command -v node >/dev/null; then \
	  (cd js && npm ci --silent --no-audit --no-fund) && node --test js/test/*.test.mjs && \
	  $(BIN)/python -m conformance --impl "node js/cli.mjs" --level geometry; fi

# the tests marked slow: every corpus file's recorded error bound against an independent measure,
# at 1e-6 and 1e-4 (each encoding may take PLN_ENCODE_BUDGET seconds, default 600, before its case is skipped)
test-slow: $(STAMP)
	$(BIN)/python -m pytest -n auto --dist worksteal -m slow -rs

# a long fuzzing run of the reader (fuzz/README.md); the suite runs a short one. Crash inputs go to
# fuzz/artifacts/, and belong in fuzz/regressions/ once fixed. FUZZ_SEED=0: a seed from the clock.
FUZZ_RUNS ?= 200000
FUZZ_SEED ?= 0
fuzz: $(STAMP)
	mkdir -p fuzz/corpus fuzz/artifacts
	$(BIN)/python fuzz/seeds.py fuzz/corpus
	$(BIN)/python fuzz/fuzz_pln.py -runs=$(FUZZ_RUNS) -seed=$(FUZZ_SEED) -timeout=0 -rss_limit_mb=256 \
	  -max_len=4096 -artifact_prefix=fuzz/artifacts/ fuzz/corpus
	# mutations of the seeds through decode_mesh and (where node is) the JS decoder: foreign
	# exceptions, crashes and inputs over 2 s are counted and saved (fuzz/mutations.py)
	$(BIN)/python fuzz/mutations.py --runs 100000 --js-runs 10000 --seed 1 --save fuzz/artifacts

# plants each bug of tools/mutate.py's fixed list in a scratch copy and runs the tests that guard it
# (5-6 minutes on 2 busy cores); exit 1 if any bug survives
mutate: $(STAMP)
	$(BIN)/python tools/mutate.py

bench: $(STAMP)
	$(BIN)/python -m pip install -q -e '.[bench]'
	$(BIN)/python bench/bench_read.py
	$(BIN)/python bench/bench_pipe_rss.py

# docs/benchmarks.md: .pln against Draco, GLB and PLY over the whole corpus (hours; see bench/compare.py)
benchmarks: $(STAMP)
	$(BIN)/python -m pip install -q -e '.[bench]'
	$(BIN)/python bench/compare.py --tolerances 1e-4 --jobs 2 --timeout 1200

# every corpus file to .pln and back to OBJ, PLY, STL, OFF, GLB, glTF, USDA, USDC, USDZ, checked, each re-encoded
roundtrip: $(STAMP)
	$(BIN)/python bench/corpus_roundtrip.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis
