# The two commands: `make demo` sets up and runs the main job, `make test` sets up and runs
# the tests. Both work on a fresh machine with only Python 3.11 (see scripts/setup.sh).
.PHONY: setup demo test test-hands bench lint

setup:
	bash scripts/setup.sh

demo: setup
	MUJOCO_GL=$${MUJOCO_GL:-egl} .venv/bin/rnnpb demo $(ARGS)

# Two workers, each given whole test files (a file's shared fixtures are made once), the
# longest first (tests/conftest.py, STARTED_FIRST).
test:
	WITH_BROWSER=1 bash scripts/setup.sh
	MUJOCO_GL=$${MUJOCO_GL:-egl} MPLBACKEND=Agg .venv/bin/python -m pytest -n 2 --dist loadfile \
		--no-loadscope-reorder $(ARGS)

# The pose tracker's tests with its model, in an environment of their own (.venv-hands): the
# extra rnnpb[hands] brings protobuf < 5 and OpenCV's desktop build, so `make test` leaves it
# out and those tests skip there (docs/perception.md). scikit-image ships a test photograph.
test-hands:
	[ -x .venv-hands/bin/python ] || $${PYTHON:-python3.11} -m venv .venv-hands
	.venv-hands/bin/python -m pip install -q -e ".[dev,hands]" scikit-image
	MUJOCO_GL=$${MUJOCO_GL:-egl} MPLBACKEND=Agg .venv-hands/bin/python -m pytest -q -n 0 \
		tests/perception/test_pose.py $(ARGS)

bench: setup
	.venv/bin/rnnpb bench

# The type checker reads pyproject.toml's [tool.basedpyright]; --pythonpath points it at the
# project's environment, where the dependencies' types are.
lint: setup
	.venv/bin/ruff check src tests benchmarks tools
	.venv/bin/ruff format --check src tests benchmarks tools
	.venv/bin/basedpyright --project pyproject.toml --pythonpath .venv/bin/python
