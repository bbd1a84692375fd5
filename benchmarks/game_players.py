"""Scripted pointer players in Chromium play the mirror game (docs/dashboard.md, "The mirror
game"); how soon they are together with the robot and find its movements.

A *player* performs the shipped model's learned patterns one after another with one pointer
(the other hand coupled as the pattern needs: mirror, parallel or opposite phase), each at a
drawn size (0.4-1.0 of the taught), speed (0.7-1.4 of the taught) and place, with hand jitter
(tremor on each sample, a slowly wandering centre, an uneven pace); it moves on to the next
pattern once the page lists the one it performs as found, and does what the page's hint says
about tempo and size ("slower", "faster", "bigger"; ``--deaf``: it does not). A *scribbler*
moves the pointer along a random smooth path with a random coupling.

Targets: a player is "together" within 20 s and has found every learned movement within 3
minutes in >= 90 % of games; a scribbler is "together" on <= 5 % of its steps. Times are game
time: steps x 0.4 s (the model's step). The game runs at ``--dt`` seconds a step (0.2: twice
times faster than real time; the player moves in step with the game, so a game is the same
game); ``--realtime`` is the check of that: the game at 0.4 s a step, the player on the wall
clock (25 pointer moves a second, as a mouse), performing the first pattern of its draw until
it is found.

``--draws benchmarks/game_players_final.json`` plays the judged draws: an exam the exam ledger
knows (study ``game``; :func:`game_exam`), refused when its version was judged (make a new
version with fresh seeds, the old ones under ``excluded``, and record its fingerprint in
``src/rnnpb/experiments/exams/versions.toml``), written in the ledger when it starts and ends,
as ``rnnpb study NAME --exam`` is (``--ledger FILE``, ``--rerun-unjudged``).

    PYTHONPATH=src python benchmarks/game_players.py --draws benchmarks/game_players_final.json \
        --out results/game-exam.json
    PYTHONPATH=src python benchmarks/game_players.py --seeds 0 5          # development draws
    PYTHONPATH=src python benchmarks/game_players.py --realtime --seeds 7 1
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"]
STEP_S = 0.4  # the model's step: game time
TOGETHER_S = 20.0
ALL_FOUND_S = 180.0
SCRIBBLE_STEPS = 150

PLAYER_JS = """
(config) => {
  const canvas = document.getElementById("view");
  const rng = (() => { let s = config.seed >>> 0 || 1; return () => {
    s ^= s << 13; s >>>= 0; s ^= s >> 17; s ^= s << 5; s >>>= 0; return s / 4294967296; }; })();
  const gauss = () => Math.sqrt(-2 * Math.log(rng() + 1e-12)) * Math.cos(2 * Math.PI * rng());
  const state = { config, firstTogether: null, found: {}, together: 0, steps: 0, done: false,
    index: 0, phase: rng() * 12, size: config.size, speed: config.speed, hints: {} };
  window.__player = state;
  let centre = config.centre.slice();
  let pressed = false;
  let wander = [0, 0];
  function point(y, z) {
    const rect = canvas.getBoundingClientRect();
    const mirrored = document.getElementById("mirror-view").checked;
    const across = mirrored ? 1 - y : y;
    return { clientX: rect.left + across * rect.width, clientY: rect.top + (1 - z) * rect.height };
  }
  function fire(kind, y, z) {
    canvas.dispatchEvent(new PointerEvent(kind, { pointerId: 7, bubbles: true, isPrimary: true,
      pointerType: "mouse", buttons: kind === "pointerup" ? 0 : 1, ...point(y, z) }));
  }
  function target() {
    if (config.scribble) {
      wander = wander.map((w) => 0.9 * w + 0.02 * gauss());
      centre = centre.map((c, k) => Math.min(0.85, Math.max(0.15, c + wander[k])));
      return centre;
    }
    const cycle = config.cycles[config.order[state.index]];
    const k = Math.floor(state.phase) % cycle.length;
    const f = state.phase - Math.floor(state.phase);
    const next = cycle[(k + 1) % cycle.length];
    const y = centre[0] + state.size * ((1 - f) * cycle[k][0] + f * next[0]);
    const z = centre[1] + state.size * ((1 - f) * cycle[k][1] + f * next[1]);
    return [y + config.tremor * gauss(), z + config.tremor * gauss()];
  }
  function press() {
    const start = config.start;
    document.getElementById("coupling").value = config.scribble
      ? config.scribbleCoupling : config.couplings[config.order[state.index]];
    if (pressed) fire("pointerup", start[0], start[1]);
    fire("pointerdown", start[0], start[1]);
    pressed = true;
  }
  function advance(step) {
    if (!config.scribble && !config.deaf) {
      if (step.hint === "slower") state.speed = Math.max(0.4, state.speed * 0.96);
      if (step.hint === "faster") state.speed = Math.min(2.0, state.speed * 1.04);
      if (step.hint === "bigger") state.size = Math.min(1.5, state.size * 1.04);
    }
    if (step.hint) state.hints[step.hint] = (state.hints[step.hint] || 0) + 1;
    state.phase += state.speed * (1 + config.unevenness * gauss());
    centre = centre.map((c) => c + config.drift * gauss());
  }
  window.addEventListener("game-step", (event) => {
    const step = event.detail;
    if (state.done) return;
    state.steps = step.step + 1;
    if (step.coherent) {
      state.together += 1;
      if (state.firstTogether === null) state.firstTogether = step.step;
    }
    for (const f of step.found_at) {
      if (!(f.pattern in state.found)) state.found[f.pattern] = step.step;
    }
    if (!pressed) { state.startStep = step.step; press(); return; }
    if (!config.scribble) {
      const current = config.order[state.index];
      if (current in state.found) {
        const left = config.order.findIndex((p) => !(p in state.found));
        if (left < 0) { state.done = true; fire("pointerup", ...target()); return; }
        state.index = left;
        // the hands are where the last movement left them: take the left one again there
        press();
      }
    }
    advance(step);
    const [y, z] = target();
    fire("pointermove", y, z);
    config.start = [y, z];
  });
}
"""

REALTIME_JS = """
(config) => {
  // The wall-clock player: the same movement, its phase from the clock, 25 samples a second.
  const canvas = document.getElementById("view");
  const cycle = config.cycles[config.order[0]];
  document.getElementById("coupling").value = config.couplings[config.order[0]];
  const point = (y, z) => {
    const rect = canvas.getBoundingClientRect();
    const across = document.getElementById("mirror-view").checked ? 1 - y : y;
    return { clientX: rect.left + across * rect.width, clientY: rect.top + (1 - z) * rect.height };
  };
  const fire = (kind, y, z) => canvas.dispatchEvent(new PointerEvent(kind,
    { pointerId: 9, bubbles: true, isPrimary: true, pointerType: "mouse", buttons: 1,
      ...point(y, z) }));
  const state = { firstTogether: null, found: {}, steps: 0 };
  window.__player = state;
  window.addEventListener("game-step", (event) => {
    const step = event.detail;
    state.steps = step.step + 1;
    if (step.coherent && state.firstTogether === null) state.firstTogether = step.step;
    for (const f of step.found_at) {
      if (!(f.pattern in state.found)) state.found[f.pattern] = step.step;
    }
    state.done = config.order[0] in state.found; // it plays one pattern: found, it is done
  });
  fire("pointerdown", config.start[0], config.start[1]);
  const t0 = performance.now();
  setInterval(() => {
    const phase = (performance.now() - t0) / 1000 / 0.4 * config.speed;
    const k = Math.floor(phase) % cycle.length, f = phase - Math.floor(phase);
    const next = cycle[(k + 1) % cycle.length];
    fire("pointermove", config.centre[0] + config.size * ((1 - f) * cycle[k][0] + f * next[0]),
      config.centre[1] + config.size * ((1 - f) * cycle[k][1] + f * next[1]));
  }, 40);
}
"""


def patterns_of_model() -> tuple[tuple[str, ...], dict, dict]:
    """The shipped model's patterns, each one's left-hand cycle (view units, 12 steps, mean
    removed) and the coupling of the other hand it needs."""
    from rnnpb.analysis.dyad import movement_templates
    from rnnpb.model.io import TrainedModel
    from rnnpb.web._game import _coupling, coupling_name

    model = TrainedModel.load(ROOT / "src/rnnpb/models/set1_fast.npz")
    templates = movement_templates(model.patterns)
    cycles = {p: templates[p][:, :2].round(5).tolist() for p in model.patterns}
    couplings = {p: coupling_name(_coupling(templates[p])) for p in model.patterns}
    return tuple(model.patterns), cycles, couplings


def draw(seed: int, patterns: tuple[str, ...], scribble: bool = False) -> dict:
    """One game's drawn player (or scribbler) from ``seed``."""
    rng = np.random.default_rng([seed, 35])
    order = [str(p) for p in rng.permutation(patterns)]
    return {
        "seed": seed,
        "order": order,
        "size": float(rng.uniform(0.4, 1.0)),
        "speed": float(rng.uniform(0.7, 1.4)),
        "centre": [float(rng.uniform(0.3, 0.45)), float(rng.uniform(0.35, 0.65))],
        "tremor": 0.004,  # view units on each sample (about 1.5 px on the page's field)
        "drift": 0.001,  # view units a step: the centre wanders
        "unevenness": 0.08,  # of each step's advance of the phase
        "scribble": scribble,
        "scribbleCoupling": str(rng.choice(["mirror", "parallel", "opposite", "still"])),
    }


def play(page, url: str, config: dict, max_steps: int, realtime: bool) -> dict:
    page.goto(url)
    page.wait_for_function("document.querySelector('#model').options.length > 0")
    page.evaluate("() => { document.getElementById('model').selectedIndex = 0; }")
    page.select_option("#model", "set1_fast.npz")
    page.click("#start")
    page.wait_for_function(
        "/step [0-9]/.test(document.querySelector('#time').textContent)", timeout=120000
    )
    page.evaluate(REALTIME_JS if realtime else PLAYER_JS, config)
    while True:
        time.sleep(0.5)
        state = page.evaluate("() => window.__player")
        if state.get("done") or state["steps"] >= max_steps:
            break
    page.click("#stop")
    page.wait_for_function("document.querySelector('#status').textContent.startsWith('stopped')")
    table = page.evaluate("() => fetch('/game/log.csv').then((r) => r.text())")
    state["stalled_share"] = stalled_share(table, state.get("startStep", 0))
    return state


def stalled_share(table: str, start: int) -> float:
    """Of the steps the player moved in, the share on which the robot saw the same hands as
    the step before (the step came before the player's answer to the last: a game too fast
    for this machine)."""
    import csv
    import io

    rows = [r for r in csv.DictReader(io.StringIO(table)) if int(r["step"]) > start + 1]
    hands = [(r["page_lhy"], r["page_lhz"]) for r in rows]
    same = [a == b for a, b in zip(hands, hands[1:], strict=False)]
    return round(sum(same) / len(same), 3) if same else 0.0


# The game's targets (the ledger's names for them), each the summary's share it reads.
TARGETS = {
    "together within 20 s in >= 90 % of games": (
        "the share of players' games together with the robot within 20 s of game time",
        ">=",
        0.9,
    ),
    "every learned movement found within 3 minutes in >= 90 % of games": (
        "the share of players' games in which every learned movement was found within 180 s",
        ">=",
        0.9,
    ),
    "scribbler together on <= 5 % of its steps": (
        "the scribblers' steps together with the robot, as a share of all their steps",
        "<=",
        0.05,
    ),
}
SUMMARY_KEYS = {
    "together within 20 s in >= 90 % of games": "together_within_20s_share",
    "every learned movement found within 3 minutes in >= 90 % of games": (
        "all_found_within_3min_share"
    ),
    "scribbler together on <= 5 % of its steps": "scribbler_together_share",
}


def game_exam(path: Path):
    """The judged draws of ``path`` as an exam the exam ledger knows: study ``game``, the
    file's ``version``, its player and scribbler seeds, the targets above, and the fingerprint
    the ledger records for the game (a hash of the two seed lists). A seed among the file's
    ``excluded`` draws, or a fingerprint ``exams/versions.toml`` does not record for the
    version, is refused."""
    from types import MappingProxyType

    from rnnpb._fingerprint import values_fingerprint
    from rnnpb.errors import ConfigError
    from rnnpb.experiments.exams import Exam, ExamTarget, ExcludedDraws, check_recorded

    data = json.loads(path.read_text(encoding="utf-8"))
    seeds = {k: [int(s) for s in data[k]] for k in ("player_seeds", "scribbler_seeds")}
    excluded = tuple(ExcludedDraws(int(a), int(b), str(why)) for a, b, why in data["excluded"])
    used = sorted(s for v in seeds.values() for s in v if any(s in r for r in excluded))
    if used:
        raise SystemExit(f"{path}: draws {used} are excluded: they were used before")
    exam = Exam(
        "game",
        int(data["version"]),
        MappingProxyType({k: tuple(v) for k, v in seeds.items()}),
        (),
        (),
        excluded,
        MappingProxyType({k: ExamTarget(k, *v) for k, v in TARGETS.items()}),
        fingerprint=values_fingerprint(seeds),
    )
    try:
        check_recorded(exam)
    except ConfigError as error:
        raise SystemExit(f"{path}: {error}") from None
    return exam


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument(
        "--draws",
        type=Path,
        help="the judged draws (benchmarks/game_players_final.json): the exam, in the ledger",
    )
    parser.add_argument("--seeds", type=int, nargs=2, metavar=("FIRST", "COUNT"))
    parser.add_argument("--dt", type=float, default=0.2, help="seconds a game step takes")
    parser.add_argument("--realtime", action="store_true", help="0.4 s a step, wall clock")
    parser.add_argument("--deaf", action="store_true", help="players ignore the hints")
    parser.add_argument("--scribblers", type=int, default=None, help="scribbler games")
    parser.add_argument("--out", type=Path, default=None, help="write the results as JSON")
    parser.add_argument("--logs", type=Path, default=None, help="keep the games' logs here")
    parser.add_argument(
        "--ledger", type=Path, default=None, help="with --draws: the exam ledger to write in"
    )
    parser.add_argument(
        "--rerun-unjudged",
        action="store_true",
        help="with --draws: run again a version whose earlier runs stopped before their verdicts",
    )
    args = parser.parse_args(argv)
    exam = None
    if args.draws:
        if args.realtime or args.deaf or args.scribblers is not None or args.dt != 0.2:
            parser.error(
                "--draws plays the judged draws as the exam defines them: no --realtime, "
                "--deaf, --scribblers or --dt"
            )
        if args.out is None:
            parser.error("--draws judges the games: give --out FILE for their figures")
        exam = game_exam(args.draws)
        seeds = list(exam.seed_list("player_seeds"))
        scribblers = list(exam.seed_list("scribbler_seeds"))
    elif args.seeds:
        seeds = list(range(args.seeds[0], args.seeds[0] + args.seeds[1]))
        scribblers = list(range(args.seeds[0], args.seeds[0] + (args.scribblers or 0)))
    else:
        parser.error("give --draws FILE or --seeds FIRST COUNT")
    if exam is None:
        games, scribbles = play_games(args, seeds, scribblers)
        report(args, games, scribbles)
        return 0
    from rnnpb.experiments.exams.ledger import exam_run

    # As `rnnpb study --exam`: refused when the version was judged, written in the ledger.
    with exam_run(exam, args.out, args.ledger, args.rerun_unjudged) as record:
        games, scribbles = play_games(args, seeds, scribblers)
        summary = report(args, games, scribbles)
        record.judged(
            exam.verdicts(
                {name: summary[key] for name, key in SUMMARY_KEYS.items()},
                lambda target, value: f"{value} ({target.compare} {target.limit:g})",
            )
        )
    print(f"written in the exam ledger {record.path} as run {record.entry.run}")
    return 0


def play_games(args: argparse.Namespace, seeds: list[int], scribblers: list[int]):
    """Each player's game and each scribbler's, as the module says."""
    dt = 0.4 if args.realtime else args.dt
    from playwright.sync_api import sync_playwright

    from rnnpb.web import DashboardServer, find_models

    patterns, cycles, couplings = patterns_of_model()
    max_steps = int(round(ALL_FOUND_S / STEP_S))
    games, scribbles = [], []
    with tempfile.TemporaryDirectory(prefix="rnnpb-game-bench-") as temporary:
        work = args.logs or temporary
        server = DashboardServer(
            find_models(ROOT / "src/rnnpb/models"), host="127.0.0.1", port=0, dt=dt, workdir=work
        )
        server.start()
        try:
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
                page = browser.new_page(viewport={"width": 1200, "height": 800}, bypass_csp=True)
                url = server.url.rstrip("/") + "/game"
                for seed in seeds:
                    config = draw(seed, patterns) | {
                        "cycles": cycles,
                        "couplings": couplings,
                        "deaf": args.deaf,
                        "start": [0.62, 0.55],
                    }
                    state = play(page, url, config, max_steps, args.realtime)
                    first = state["firstTogether"]
                    found = state["found"]
                    game = {
                        "seed": seed,
                        "size": round(config["size"], 3),
                        "speed": round(config["speed"], 3),
                        "order": config["order"],
                        "together_s": None if first is None else round((first + 1) * STEP_S, 1),
                        "found_s": {p: round((s + 1) * STEP_S, 1) for p, s in found.items()},
                        "all_found_s": (
                            round((max(found.values()) + 1) * STEP_S, 1)
                            if len(found) == len(patterns)
                            else None
                        ),
                        "hints": state.get("hints", {}),
                        "stalled_share": state["stalled_share"],
                    }
                    game["won"] = (
                        game["together_s"] is not None
                        and game["together_s"] <= TOGETHER_S
                        and game["all_found_s"] is not None
                        and game["all_found_s"] <= ALL_FOUND_S
                    )
                    games.append(game)
                    print(json.dumps(game), flush=True)
                for seed in scribblers:
                    config = draw(seed, patterns, scribble=True) | {
                        "cycles": cycles,
                        "couplings": couplings,
                        "deaf": True,
                        "start": [0.62, 0.55],
                    }
                    state = play(page, url, config, SCRIBBLE_STEPS, False)
                    share = state["together"] / max(state["steps"], 1)
                    scribbles.append(
                        {"seed": seed, "steps": state["steps"], "together_share": round(share, 3)}
                    )
                    print(json.dumps(scribbles[-1]), flush=True)
                browser.close()
        finally:
            server.stop()
    return games, scribbles


def report(args: argparse.Namespace, games: list, scribbles: list) -> dict:
    """The games' shares, printed, and written to ``--out``."""
    dt = 0.4 if args.realtime else args.dt
    summary = {
        "dt": dt,
        "realtime": args.realtime,
        "deaf": args.deaf,
        "games": len(games),
        "won_share": round(float(np.mean([g["won"] for g in games])), 3) if games else None,
        "together_within_20s_share": (
            round(
                float(
                    np.mean([g["together_s"] is not None and g["together_s"] <= 20 for g in games])
                ),
                3,
            )
            if games
            else None
        ),
        "all_found_within_3min_share": (
            round(
                float(
                    np.mean(
                        [g["all_found_s"] is not None and g["all_found_s"] <= 180 for g in games]
                    )
                ),
                3,
            )
            if games
            else None
        ),
        "scribbler_together_share": (
            round(
                float(sum(s["together_share"] * s["steps"] for s in scribbles))
                / max(sum(s["steps"] for s in scribbles), 1),
                3,
            )
            if scribbles
            else None
        ),
    }
    if args.realtime:  # one pattern a game: "won" and "all found" do not apply
        summary["won_share"] = summary["all_found_within_3min_share"] = None
        summary["first_pattern_found_s"] = [g["found_s"].get(g["order"][0]) for g in games]
    print(json.dumps(summary, indent=1))
    if args.out:
        args.out.write_text(
            json.dumps({"summary": summary, "games": games, "scribblers": scribbles}, indent=1)
        )
    return summary


if __name__ == "__main__":
    sys.exit(main())
