"""The mirror game page (/game) in a real headless Chromium with its CSP in force: two robots
play, and a person's hands reach the robot; its messages are checked like the dashboard's."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rnnpb.analysis import dyad as measures
from rnnpb.web import ProtocolError, parse_client_message

from .test_browser import WATCH_CSP, _until, browser  # noqa: F401 — the browser fixture


def _game_page(browser, server):  # noqa: F811
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.add_init_script(WATCH_CSP)
    page.goto(server.url.rstrip("/") + "/game")
    return page, errors


def test_two_robots_play_and_the_page_shows_the_measures(browser, server, tmp_path):  # noqa: F811
    page, errors = _game_page(browser, server)
    try:
        _until(page, "document.querySelector('#model').options.length > 0", 30000)
        page.select_option("#mode", "robots")
        page.click("#start")
        _until(page, "/step [1-9][0-9]/.test(document.querySelector('#time').textContent)", 90000)
        meter = float(page.eval_on_selector("#meter", "m => m.value"))
        assert 0.0 <= meter <= 1.0
        assert "of" in page.text_content("#found")
        page.screenshot(path=str(tmp_path / "game.png"))
        # The person's hands: the page sends them and the robot sees them. One game at a
        # time: Start is off while the robots play.
        assert page.is_disabled("#start")
        page.click("#stop")
        _until(page, "!document.querySelector('#start').disabled", 20000)
        page.select_option("#mode", "person")
        page.click("#start")
        _until(page, "/step [1-9][0-9]/.test(document.querySelector('#time').textContent)", 90000)
        box = page.locator("#view").bounding_box()
        page.mouse.move(box["x"] + 0.62 * box["width"], box["y"] + 0.45 * box["height"])
        page.mouse.down()
        page.mouse.move(box["x"] + 0.70 * box["width"], box["y"] + 0.35 * box["height"])
        page.mouse.up()
        page.click("#stop")
        _until(page, "document.querySelector('#status').textContent.startsWith('stopped')", 20000)
        violations = page.evaluate("window.__cspViolations || []")
        assert not violations, violations
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


@pytest.mark.parametrize(
    "message, problem",
    [
        ({"type": "game", "action": "fly", "mode": "person", "model": None}, "game action"),
        ({"type": "game", "action": "start", "mode": "solo", "model": None}, "game mode"),
        ({"type": "game", "action": "start", "mode": "person", "model": 3}, "game model"),
        ({"type": "game", "action": "start", "mode": "person"}, "needs field"),
        ({"type": "game_hands", "hands": [0.1, 0.2, 2.0, 0.5]}, "rhy"),
        ({"type": "game_hands", "hands": [0.1, 0.2]}, "4 values"),
    ],
)
def test_bad_game_messages_are_refused(message, problem):
    with pytest.raises(ProtocolError, match=problem):
        parse_client_message(json.dumps(message))


def test_game_messages_are_normalized():
    hands = parse_client_message(json.dumps({"type": "game_hands", "hands": [0.1, None, 0.5, 1]}))
    assert hands["type"] == "game_hands" and hands["hands"][2] == 0.5
    start = parse_client_message(
        json.dumps({"type": "game", "action": "start", "mode": "robots", "model": "set1"})
    )
    assert start == {"type": "game", "action": "start", "mode": "robots", "model": "set1"}


# --- playing the game ------------------------------------------------------------------------

_PRESS = """(args) => {
  const canvas = document.getElementById("view");
  const rect = canvas.getBoundingClientRect();
  const mirrored = document.getElementById("mirror-view").checked;
  for (const [kind, id, y, z] of args) {
    const across = mirrored ? 1 - y : y;
    canvas.dispatchEvent(new PointerEvent(kind, { pointerId: id, bubbles: true,
      isPrimary: id === 1, pointerType: "touch", buttons: kind === "pointerup" ? 0 : 1,
      clientX: rect.left + across * rect.width, clientY: rect.top + (1 - z) * rect.height }));
  }
}"""

_PLAYER = """(config) => {
  // Performs each pattern's left-hand cycle with one pointer, the other hand coupled, one
  // twelfth of a cycle a game step, and moves on once the page lists the pattern as found.
  const canvas = document.getElementById("view");
  const state = { found: {}, together: null, index: 0, phase: 0, pressed: false, at: [0.62, 0.55] };
  window.__player = state;
  const fire = (kind, y, z) => {
    const rect = canvas.getBoundingClientRect();
    canvas.dispatchEvent(new PointerEvent(kind, { pointerId: 3, bubbles: true, isPrimary: true,
      pointerType: "mouse", buttons: 1, clientX: rect.left + (1 - y) * rect.width,
      clientY: rect.top + (1 - z) * rect.height }));
  };
  const press = () => {
    document.getElementById("coupling").value = config.couplings[config.order[state.index]];
    if (state.pressed) fire("pointerup", ...state.at);
    fire("pointerdown", ...state.at);
    state.pressed = true;
  };
  window.addEventListener("game-step", (event) => {
    const step = event.detail;
    if (step.coherent && state.together === null) state.together = step.step;
    for (const f of step.found_at) {
      if (!(f.pattern in state.found)) state.found[f.pattern] = step.step;
    }
    if (!state.pressed) { press(); return; }
    if (state.index < 0) return;
    if (config.order[state.index] in state.found) {
      state.index = config.order.findIndex((p) => !(p in state.found));
      if (state.index < 0) return;
      press();
    }
    const cycle = config.cycles[config.order[state.index]];
    state.phase += 1;
    const c = cycle[state.phase % cycle.length];
    state.at = [config.centre[0] + config.size * c[0], config.centre[1] + config.size * c[1]];
    fire("pointermove", ...state.at);
  });
}"""


def _start_person_game(page):
    _until(page, "document.querySelector('#model').options.length > 0", 30000)
    page.select_option("#mode", "person")
    page.click("#start")
    _until(page, "/step [1-9]/.test(document.querySelector('#time').textContent)", 90000)


def test_a_press_takes_the_hand_aimed_at_one_pointer_couples_two_fingers_do_not(
    browser,  # noqa: F811
    server,
):
    page, errors = _game_page(browser, server)
    try:
        _start_person_game(page)
        game = server.app.state.game
        # Mirror view (the default): the left hand's marker is on the left of the field.
        assert page.is_checked("#mirror-view")
        page.select_option("#coupling", "mirror")
        # Aim at the left marker (view 0.62, 0.55, drawn at x = 0.38): the left hand moves up
        # and, mirrored, the right hand too, by as much; a second drag does not drift it.
        page.evaluate(
            _PRESS,
            [["pointerdown", 1, 0.62, 0.55], ["pointermove", 1, 0.70, 0.65]],
        )
        page.wait_for_timeout(300)
        lhy, lhz, rhy, rhz = game.person.raw
        assert (lhy, lhz) == pytest.approx((0.70, 0.65), abs=0.01)
        assert (rhy, rhz) == pytest.approx((0.30, 0.65), abs=0.01)
        page.evaluate(_PRESS, [["pointermove", 1, 0.62, 0.55], ["pointerup", 1, 0.62, 0.55]])
        page.wait_for_timeout(300)
        assert game.person.raw == pytest.approx([0.62, 0.55, 0.38, 0.55], abs=0.01)
        # Two fingers: each drags the hand it pressed, the other hand does not follow.
        page.evaluate(
            _PRESS,
            [
                ["pointerdown", 1, 0.62, 0.55],
                ["pointerdown", 2, 0.38, 0.55],
                ["pointermove", 1, 0.62, 0.75],
                ["pointermove", 2, 0.30, 0.40],
            ],
        )
        page.wait_for_timeout(300)
        assert game.person.raw == pytest.approx([0.62, 0.75, 0.30, 0.40], abs=0.01)
        page.evaluate(_PRESS, [["pointerup", 1, 0.62, 0.75], ["pointerup", 2, 0.30, 0.40]])
        page.click("#stop")
        _until(page, "document.querySelector('#status').textContent.startsWith('stopped')", 20000)
        assert not page.evaluate("() => window.__cspViolations || []")
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


def test_every_learned_pattern_played_with_one_pointer_is_found_and_logged(
    browser,  # noqa: F811
    server,
    model,
):
    from rnnpb.web._game import _coupling, coupling_name

    templates = measures.movement_templates(model.patterns)
    config = {
        "order": list(model.patterns),
        # Half the taught size, away from where the robot saw its teachers' hands.
        "size": 0.5,
        "centre": [0.55, 0.45],
        "cycles": {p: templates[p][:, :2].tolist() for p in model.patterns},
        "couplings": {p: coupling_name(_coupling(templates[p])) for p in model.patterns},
    }
    assert sorted(set(config["couplings"].values())) == ["mirror", "opposite", "parallel"]
    page, errors = _game_page(browser, server)
    try:
        _start_person_game(page)
        page.evaluate(_PLAYER, config)
        every = len(model.patterns)
        page.wait_for_function(
            f"() => Object.keys(window.__player.found).length === {every}", timeout=150000
        )
        player = page.evaluate("() => window.__player")
        # Together within 20 s of game time at the model's 0.4 s step.
        assert player["together"] is not None and player["together"] * 0.4 <= 20
        assert page.locator("#found-list li").count() == every
        page.click("#stop")
        _until(page, "document.querySelector('#status').textContent.startsWith('stopped')", 20000)
        log = json.loads(page.evaluate("() => fetch('/game/log.json').then((r) => r.text())"))
        assert [f["pattern"] for f in log["found"]] == sorted(
            player["found"], key=player["found"].get
        )
        assert all(f["led_by"] in ("robot", "you", "") for f in log["found"])
        table = page.evaluate("() => fetch('/game/log.csv').then((r) => r.text())")
        header, *rows = table.strip().splitlines()
        assert header.split(",")[:2] == ["step", "time_s"] and len(rows) >= log["steps"] - 1
        # The game's clock starts at its first step, not before the step's compilation.
        assert rows[0].split(",")[:2] == ["0", "0.0"]
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


# --- the game's measures ---------------------------------------------------------------------


def test_velocity_agreement_ignores_size_and_place_tolerates_a_lag_and_sees_disagreement():
    from rnnpb.web._game import velocity_agreement

    templates = measures.movement_templates()
    cycle = np.tile(templates["3"], (3, 1))  # three cycles of a circle, (36, 4)
    centre = np.array([0.7, 0.7, 0.3, 0.7])
    robot = centre + cycle
    # Smaller, elsewhere and one step behind: still in full agreement.
    person = np.roll(0.4 + 0.3 * cycle, 1, axis=0)
    assert velocity_agreement(robot, person) == pytest.approx(1.0, abs=1e-6)
    assert velocity_agreement(robot, np.roll(person, 1, axis=0)) == pytest.approx(1.0, abs=1e-6)
    # Half a cycle out of phase, another pattern, or still: no agreement.
    assert velocity_agreement(robot, centre + np.roll(cycle, 6, axis=0)) < 0.1
    swing = centre + np.tile(templates["2"], (3, 1))
    assert velocity_agreement(robot, swing) < 0.5
    assert velocity_agreement(robot, np.tile(centre, (36, 1))) == 0.0


def test_the_player_frame_shows_a_small_movement_off_centre_at_the_taught_size_and_place():
    from rnnpb.web._game import PlayerFrame, taught_frame

    templates = measures.movement_templates()
    centre, size = taught_frame()
    frame = PlayerFrame(centre, size)
    here = np.array([0.4, 0.4, 0.2, 0.4])
    seen = []
    for step in range(48):
        view = here + 0.5 * templates["1"][step % 12]
        frame.push(view)
        seen.append(frame.seen(view))
    seen = np.asarray(seen[-24:])
    assert seen.mean(axis=0) == pytest.approx(centre, abs=0.01)
    # As large as the teachers' movements (half the size here), within a quarter.
    assert np.sqrt(np.mean((seen - seen.mean(axis=0)) ** 2)) == pytest.approx(size, rel=0.25)
    assert frame.back(frame.seen(here)) == pytest.approx(here, abs=1e-9)
    # Still hands stay still: their jitter is not enlarged into a movement.
    still = PlayerFrame(centre, size)
    rng = np.random.default_rng(0)
    for _ in range(24):
        still.push(here + 0.002 * rng.standard_normal(4))
    assert still.gain * 0.002 < 0.01


def test_a_figure_eight_s_cycle_is_its_own_however_often_it_crosses_its_middle():
    from rnnpb.web._game import _period

    angle = 2 * np.pi * np.arange(48) / 12

    def eight(height: float) -> np.ndarray:
        """Up and down twice in each 12-step cycle, the hands mirrored."""
        across, up = 0.08 * np.sin(angle), height * np.sin(2 * angle)
        return np.stack([0.6 + across, 0.5 + up, 0.4 - across, 0.5 + up], axis=1)

    tall, wide = eight(0.16), eight(0.02)
    assert _period(tall) == 12
    assert _period(wide) == 12
    still = np.full((48, 4), 0.5)
    assert np.isnan(_period(still))


def test_no_hint_leads_back_to_a_movement_found_already():
    from rnnpb.web._game import PlayerFrame, hint, taught_frame

    templates = measures.movement_templates()
    centre = np.array([0.62, 0.55, 0.38, 0.55])
    robot = centre + np.tile(templates["1"], (4, 1))  # the horizontal swing, mirrored
    parallel = templates["1"] * np.array([1, 1, -1, 1])  # the same swing, hands parallel
    person = centre + np.tile(parallel, (4, 1))
    frame = PlayerFrame(*taught_frame())
    for view in person[-24:]:
        frame.push(view)
    assert hint(person, person, robot, frame, 0.2) == "the other hand mirror"
    told = hint(person, person, robot, frame, 0.2, found_already="1")
    assert "mirror" not in told and "movement 1" in told and "found" in told
