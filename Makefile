# The two entry points of the README. Each sets the machine up first (idempotent).
PY ?= python3
OUT ?= out/pipeline

.PHONY: setup setup-test run test
setup:
	@bash tools/setup.sh

setup-test:
	@bash tools/setup.sh test

run: setup
	staregen pipeline --out $(OUT)

test: setup-test
	$(PY) -m pytest -q -n 2
