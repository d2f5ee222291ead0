.PHONY: help install dev test test-rust test-py fmt lint bench bench-peers profile screenshots

help: ## list the targets
	@grep -E '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | awk -F':.*## ' '{printf "  %-12s %s\n", $$1, $$2}'

install: ## install mmusv (release build of the extension)
	python3 -m pip install .

dev: ## editable install with test extras
	python3 -m pip install -e ".[test]"

test: ## everything CI runs (installs what it needs)
	bash scripts/test.sh

test-rust: ## Rust unit tests of the core (no Python)
	cargo test -p mmusv-core --release

test-py: ## pytest only (after `make dev`)
	python3 -m pytest -q -p no:dash tests

fmt: ## format Rust and Python
	cargo fmt --all
	python3 -m ruff format python tests benches

lint: ## rustfmt + clippy + ruff + mypy + stubtest (as CI runs them)
	cargo fmt --all --check
	cargo clippy -p mmusv-core -p mmusv-benches -p mmusv-py --release --all-targets -- -D warnings
	python3 -m ruff check python tests benches
	python3 -m ruff format --check python tests benches
	python3 -m mypy
	python3 -m mypy.stubtest mmusv._core

bench: ## criterion benchmarks: ray casting, sensors, radar, sea camera (rays/s; minutes: see README, Speed)
	cargo bench -p mmusv-benches

bench-peers: ## mmusv vs Open3D/Embree: same scene, rays and threads, hits checked equal first (pip install '.[bench]')
	python3 benches/compare_open3d.py

profile: ## where the main job's time goes, per stage per frame (50 frames of scenarios/port_entry.yaml)
	python3 benches/profile_run.py

screenshots: ## the editor screenshots in docs/editor/ (the browser tests, saving their pictures there)
	MMUSV_EDITOR_SCREENSHOTS=docs/editor python3 -m pytest -q -p no:dash tests/editor/test_browser.py
