# Every target creates the virtual environment it needs (.venv), from pyproject.toml.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
DINO := ../shared/data/dinosaur

.PHONY: bench-symmetry bench-turning bench-records bench-printed bench-variants-parts bench-clock docs demo test test-slow test-floor lint bench bench-memory bench-real bench-variants bench-accuracy bench-accuracy-paths bench-accuracy-csrt bench-accuracy-given-fov bench-accuracy-reseed bench-random bench-hard clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev,dask,plot]'
	touch $(STAMP)

## demo: measure the bundled sample clip (truth: 0.6 rad/s, ccw)
demo: $(STAMP)
	$(BIN)/rotrate analyze sample_videos/box_ortho.mp4 --fixation 319.5,179.5

## test: the default suite (unit, CLI, sample-clip regression, paper Table I, dinosaur)
test: $(STAMP)
	$(BIN)/python -m pytest -q --numprocesses=auto --maxprocesses=4

## test-slow: longer suites (rendering on the fly, long clips)
test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow

## test-floor: the declared oldest dependency versions (constraints/floor.txt), in .venv-floor: the fast core of the suite
FLOOR := .venv-floor
$(FLOOR)/.installed: pyproject.toml constraints/floor.txt
	$(PYTHON) -m venv $(FLOOR)
	$(FLOOR)/bin/pip install --quiet --upgrade pip
	$(FLOOR)/bin/pip install --quiet -c constraints/floor.txt -e '.[dev]'
	touch $(FLOOR)/.installed

test-floor: $(FLOOR)/.installed
	$(FLOOR)/bin/python -m pytest -q tests/test_decode.py tests/test_cli.py tests/test_cli_polish.py tests/test_samples.py tests/test_rates.py tests/test_view.py tests/test_real_files.py

## docs: docs/cli.md made again from the commands' help (tests/test_docs.py fails when it is stale)
docs: $(STAMP)
	$(BIN)/python -m rotrate_cli.cli.docs > docs/cli.md

## lint: ruff, and the import contracts that keep machinery below the stages (import-linter, pyproject.toml)
lint: $(STAMP)
	$(BIN)/ruff check rotrate_cli tests benchmarks
	$(BIN)/lint-imports

## bench: analyze vs decode-only time at 720p and 1080p and on the real record clip, start-up, and peak memory for a clip and one 4x as long
bench: $(STAMP)
	$(BIN)/python benchmarks/bench_speed.py

## bench-memory: peak memory of --fixation auto on 640x480 clips of 1, 10 and 30 minutes (about 4 minutes)
bench-memory: $(STAMP)
	$(BIN)/python benchmarks/bench_speed.py --long

## bench-real: real footage with known truth (../shared/data), default settings: error, interval, coverage, sense
bench-real: $(STAMP)
	$(BIN)/python benchmarks/bench_real.py

## bench-variants: the real videos mirrored, turned, shrunk, thinned, reversed, noisy, cropped, rolled, wobbling and coming nearer (written once to bench_out/variants): rate, interval and sense of turning, default settings (about a minute)
bench-variants: $(STAMP)
	$(BIN)/python benchmarks/bench_variants.py

## bench-variants-parts: each of those copies cut to 0.3 and 0.6 of a turn from 2 s and 0.9 from 8 s (96 parts, about 13 minutes): none called good that is off
bench-variants-parts: $(STAMP)
	$(BIN)/python benchmarks/bench_variants.py --parts

## bench-clock: clocks under a turn (a second hand sweeping or stepping, the face tilted, a camera rolling and wobbling), default settings (renders cached in bench_out/clock)
bench-clock: $(STAMP)
	$(BIN)/python benchmarks/bench_clock.py

## bench-accuracy: the paper's method vs ours on 17 rendered conditions with known rates, no lens given (renders cached)
bench-accuracy: $(STAMP)
	$(BIN)/python benchmarks/bench_accuracy.py

## bench-accuracy-paths: the same suite with the axis angle from the tracks' paths (--angle-from paths)
bench-accuracy-paths: $(STAMP)
	$(BIN)/python benchmarks/bench_accuracy.py --angle-from paths

## bench-accuracy-csrt: the same suite with --tracker csrt on the automatic points
bench-accuracy-csrt: $(STAMP)
	$(BIN)/python benchmarks/bench_accuracy.py --tracker csrt

## bench-accuracy-given-fov: the same suite with the perspective clips' true field of view given (--fov DEG)
bench-accuracy-given-fov: $(STAMP)
	$(BIN)/python benchmarks/bench_accuracy.py --given-fov

## bench-accuracy-reseed: the same 17 conditions rendered with other seeds (other textures and noise; about 5 minutes the first time)
bench-accuracy-reseed: $(STAMP)
	$(BIN)/python benchmarks/bench_accuracy.py --reseed 1000

## bench-hard: a hand's shake, flickering light, turns of tens of degrees a frame and motion blur done to renders, measured with default settings (about 3 minutes the first time)
bench-hard: $(STAMP)
	$(BIN)/python benchmarks/bench_hard.py

## bench-symmetry: fans, spokes, checkered discs and drums whose picture repeats 2-16 times a turn, face on, tilted and from the side, slow and at 20-40 degrees a frame: right within 0.5% or weak, never a multiple called good (renders cached in bench_out/symmetry; about 2 minutes the first time)
bench-symmetry: $(STAMP)
	$(BIN)/python benchmarks/bench_symmetry.py

## bench-turning: flat rotors rendered under a turn (0.3), face on and tilted, axis in and out of the frame (about a minute)
bench-turning: $(STAMP)
	$(BIN)/python benchmarks/bench_turning.py

## bench-records: records under a turn (grooves alike at every angle, a photographed label, dust, a still highlight and tonearm), face on and tilted 30-65 degrees, axis in and below the frame, 0.3 and 0.6 of a turn, H.264 (renders cached in bench_out/records; about two minutes the first time; skips without ../shared)
bench-records: $(STAMP)
	$(BIN)/python benchmarks/bench_records.py

## bench-printed: discs printed with the shared real photographs, a third of a turn before a 45-degree lens, face on and tilted 45-72 degrees, axis in and below the frame, H.264 (renders cached in bench_out/printed; about two minutes the first time; skips without ../shared)
bench-printed: $(STAMP)
	$(BIN)/python benchmarks/bench_printed.py

## bench-random: 20 random rendered conditions (lenses to 75 degrees, 2-6 s, elevation to 60) measured with default settings and --fixation auto (about 10 minutes the first time)
bench-random: $(STAMP)
	$(BIN)/python benchmarks/bench_random.py

clean:
	rm -rf $(VENV) $(FLOOR) .pytest_cache .ruff_cache bench_out
