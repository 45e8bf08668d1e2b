"""The lesson's steps: the drop each shows, its scene and its text (plain data, no widgets).

Each step sets the drop and the scene, says what to look for, and asks for a prediction before
it reveals the answer. The numbers quoted in the answers are the solver's own for that step's
drop (tests/app/test_app_lesson.py recomputes each with ``twoball.simulate``). The state reads
them for a URL's ``?step=N`` (app/state.py), the lesson's card shows them (app/lesson.py).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from twoball import presets

HEIGHT = 1e4  # about a 1 m drop (twoball.presets), and the height of the shipped map
TENNIS = presets.PRESETS["tennis"]


@dataclass(frozen=True)
class Step:
    """One step: the drop it shows (the model's parameters), the scene, the text."""

    title: str
    scene: str
    drop: dict = field(repr=False)
    look_for: str
    question: str
    choices: tuple[str, ...]
    answer: int  # index into choices
    explanation: str
    # a line under the answer in the main area, where the class looks, for what the revealed
    # scene shows beyond the question: step 1's plot goes on to a second bounce, the tallest
    # thing on screen, which only the end of the card's explanation named (below a projector's
    # screen). Said, not cut: the drop scene ends at the second apex for every drop, and the
    # steps that follow compare the two bounces
    aside: str = ""


def gist(explanation: str) -> tuple[str, str]:
    """An explanation's first sentence (the answer and its numbers) and the rest ("" if none).
    A projector's card shows the first and folds the rest away (app/lesson.py), so each
    explanation's first sentence says the answer with its numbers, on its own."""
    parts = re.split(r"(?<=\.)\s+(?=[A-Z(])", explanation, maxsplit=1)
    return parts[0], parts[1] if len(parts) > 1 else ""


STEPS = (
    Step(
        title="The textbook prediction",
        scene="drop",
        drop={"eps": 1.0, "eps12": None, "mu": 0.01, "tau_ratio": 1.0, "height": HEIGHT},
        look_for="Two perfectly bouncy balls, the top one a hundred times lighter, dropped "
        "together from about 1 m with a small gap between them. The orange curve is the small "
        "ball's height, the blue one the big ball's, the dotted green line what the textbook "
        "predicts.",
        question="How high does the small ball go, compared with the height it was dropped from?",
        choices=("Back to the same height", "Twice as high", "About 4 times", "About 8 to 9 times"),
        answer=3,
        explanation="About 8.5 times: dropped from 1.04 m, it rises to 8.8 m. The textbook "
        "argument (the independent contact model): the big ball bounces off the floor first "
        "and meets the small ball still falling; "
        "seen from the big ball, the small ball comes in at twice the fall speed and leaves at "
        "twice it, so it goes up at three times the fall speed: 3 x 3 = 9 times the height for "
        "a very light ball. The model's small ball goes a little above the textbook's line (8.7 "
        "m): its balls are springy and touch for a while, where the textbook's collide in an "
        "instant; the textbook is right to within 2 %. (Its second bounce goes higher still, "
        "to 21.1 m, when the balls meet again: the summary calls any h2 > h1 a delayed "
        "rebound. The surprise of step 3 is another: a first bounce far below the textbook's.)",
        aside="The second peak, h2 = 21.1 m, comes after the balls meet again; any h2 above "
        "h1 counts as a delayed rebound. Step 3 shows another kind.",
    ),
    Step(
        title="A tennis ball held a little above a basketball",
        scene="drop",
        drop={
            "eps": TENNIS.eps,
            "eps12": TENNIS.eps12,
            "mu": TENNIS.mu,
            "tau_ratio": 1.0,
            "height": HEIGHT,
        },
        look_for="Real balls from the rule books: a basketball (it keeps 85 % of its speed in "
        "a bounce), a tennis ball (75 %, ten times lighter), held a little apart and dropped "
        "from 1 m. (The tennis preset holds them touching: step 4 tells that story.)",
        question="Real balls lose energy. How high does the tennis ball go now?",
        choices=(
            "Lower than it was dropped from",
            "About as high",
            "About 3.7 times as high",
            "About 9 times as high",
        ),
        answer=2,
        explanation="About 3.7 times (3.8 m from 1.04 m), still far above the drop height, and "
        "just what the "
        "textbook prediction says for these balls (the green line): the two collisions are "
        "separate, the floor's first, then the balls'.",
    ),
    Step(
        title="A ping-pong ball: the delayed rebound",
        scene="drop",
        drop={"eps": 0.9, "eps12": None, "mu": 0.01, "tau_ratio": 0.01, "height": HEIGHT},
        look_for="Now a much lighter ball, a hundred times lighter (a real ping-pong ball, the "
        "ping-pong preset, is lighter still), held touching the big one. Think of the small "
        "ball's first two bounces (the peaks of the orange curve, once revealed).",
        question="Which bounce of the small ball is higher?",
        choices=("The first", "The second", "Both the same"),
        answer=1,
        explanation="The second, about 5 times higher than the first (5.0 m against 0.92 m): a "
        "delayed rebound. The first bounce does not even reach the 1 m it was dropped from, far "
        "below the textbook's prediction (the green line, 6.6 m).",
    ),
    Step(
        title="Why: several contacts in one collision",
        scene="closeup",
        drop={"eps": 0.9, "eps12": None, "mu": 0.01, "tau_ratio": 0.01, "height": HEIGHT},
        look_for="The same drop, slowed down to the first collision: the forces of the floor "
        "and between the balls while the big ball is squashed against the floor.",
        question="How many times do the balls touch while the big ball is on the floor?",
        choices=("Once", "Twice", "4 times", "Hundreds of times"),
        answer=2,
        explanation="4 times: the small ball is hit while the big one is still being squashed, "
        "bounces off, falls back and is hit again, each time before the big ball has given "
        "back its energy. It leaves with little of it: the small first bounce. The energy left "
        "in the big ball comes back at the next collision: the high second bounce. (A tennis "
        "ball held touching, the tennis preset, is hit once only, but also while the big ball "
        "is still squashed: its first bounce is small and its second higher, for the same "
        "reason.)",
    ),
    Step(
        title="Where delayed rebounds happen",
        scene="map",
        drop={"eps": 0.9, "eps12": None, "mu": 0.01, "tau_ratio": 0.01, "height": HEIGHT},
        look_for="The map shows, for every mass ratio (across) and gap (up), h2/h1: red "
        "where the second bounce is higher (a delayed rebound, inside the black outlines), "
        "blue where the first is. The star is the drop of the last step. A click chooses "
        "those balls for the other tabs.",
        question="Which drops give a delayed rebound?",
        choices=(
            "A heavy top ball, held far apart",
            "A light top ball, held close to the big one",
            "Every drop",
            "None with real balls",
        ),
        answer=1,
        explanation="The map is red there for top balls up to about a third of the big "
        "ball's mass, the second bounce up to nearly 7 times the first: the collisions overlap "
        "in time, as in the close-up. Far apart, they are separate and a light ball's first "
        "bounce is the textbook's; only top balls much lighter than the big one (mostly below "
        "a thirtieth of its mass) still bounce higher the second time, when the balls meet "
        "again as in step 1, and by at most 1.5 times.",
    ),
    Step(
        title="How sure can we be?",
        scene="accuracy",
        drop={"eps": 0.9, "eps12": None, "mu": 0.01, "tau_ratio": 0.01, "height": HEIGHT},
        look_for="The same drop solved by general-purpose methods at several tolerances: each "
        "point is a run time (across) against an error (up); the point named exact in the "
        "legend is this app's own solver.",
        question="A general-purpose solver is asked for 6 correct digits. Does it give them?",
        choices=("Always", "Not always: its error can be far larger than asked", "Never"),
        answer=1,
        explanation="Not always: errors 10 to 1000 times the tolerance are common, and a brief "
        "contact can be missed altogether. The exact solver solves each contact in closed "
        "form and cannot miss one: its answers are good to about 10 digits, in a fraction of "
        "a millisecond.",
    ),
)
