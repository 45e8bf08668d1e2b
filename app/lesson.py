"""The lesson: a guided path through the demonstration, one step per idea.

Each step sets the drop and the scene, says what to look for, and asks for a prediction before
it reveals the answer: until then the scene is covered (app/explorer.py), so that a class
shown the step predicts before it sees. The numbers quoted in the answers are the solver's own
for that step's drop (tests/app/test_app_lesson.py recomputes each with ``twoball.simulate``).
The step is in the URL (``?step=3``), so a teacher can send a class to one step.
"""

from __future__ import annotations

import panel as pn
import param

from .scene import Built, ScriptedButton, alert, join, later
from .state import ExplorerState
from .steps import STEPS, gist

# what the lesson sets and gives back at its end: the drop, the scene and the units
BEFORE_THE_LESSON = ("eps", "eps12", "mu", "tau_ratio", "height", "scene", "units")
# the question, its choices and the answer in the main area: large on a laptop or a phone,
# read from the back of a room in presentation mode
ASKED = {"font-size": "20px", "line-height": "1.4"}
PROJECTED = {"font-size": "30px", "line-height": "1.3"}
# what to look for, on a projector: smaller than the question (at 30 px step 1's five lines had
# pushed Reveal below a 1280x720 screen); still read from the back of a room
PROJECTED_LOOK_FOR = {"font-size": "24px", "line-height": "1.3"}
# Under a projected answer, the step's aside (step 1's two lines) at the page's own 20 px, and
# both with little margin: at 24 px, with a paragraph's margins, they put the plot 196 px
# under the answer line's top (a teacher's trial; the row under the plot, off the screen)
PROJECTED_ASIDE = {"font-size": "20px", "line-height": "1.3"}
TIGHT = ":host p { margin-top: 0.2em; margin-bottom: 0.2em; }"
# each circle centred on its words: Bokeh lifts a radio's words by 0.4 em, made for its own
# 13 px circle and text; larger, the circle sat below them (a third of a line on a projector)
CENTRED = (
    ":host label { display: flex; align-items: center; gap: 0.3em; } :host input { flex: none; } "
    ":host label > input + span { top: 0; }"
)
ASKED_CHOICES = f":host {{ font-size: 18px; }} {CENTRED}"
PROJECTED_CHOICES = (
    f":host {{ font-size: 30px; }} :host input {{ width: 26px; height: 26px; }} {CENTRED}"
)


# A phone (narrower than 768 px: PAGE_CSS in app/explorer.py) shows the card below the scene
# and the controls. After a reveal the page scrolled down to the card's answer, past the plot it
# talks about: the student read "it rises to 8.8 m" with the plot out of sight above. Decided:
# on a phone the answer stands above the scene, where the question was (as the step's aside
# already does), the page scrolled to its top, and the scene's plot follows it; the card keeps
# the step's title and Previous/Next (below, where the student scrolls on to, after the plot).
# Not the plot at the top with the answer under it: the answer then lay under the whole scene
# (the animation and the player come between), a screen and more below the plot. A laptop's
# and a projector's card beside the scene keep the answer. Two alerts of the same text, each
# shown at its own widths (a Panel pane has one place in a page).
PHONE = "@media (max-width: 767px) { :host { display: none !important; } }"
WIDE = "@media (min-width: 768px) { :host { display: none !important; } }"
# The answer in a projector's card (the 330 px sidebar, at the room's 20 px). The whole
# explanation ran past a 1280x720 screen on four steps (to y 1343 on step 1, step 6's cut
# mid-sentence). Decided: the room reads the one-line answer above the scene, and the teacher
# tells the why; the card shows the explanation's first sentence (the answer with its numbers,
# steps.gist) at 18 px, the teacher's prompt, and folds the rest under FULL_EXPLANATION, which
# the teacher opens when the class asks (the sidebar then scrolls). Not smaller text (under
# 16 px it is not read from a lectern either), not a second column (the main area's width is
# the plots'). A laptop's and a phone's card, read by the student alone, keep it whole.
FULL_EXPLANATION = "The full explanation"
PROJECTED_ANSWER = {"font-size": "18px"}
FOLD_CSS = ":host summary { cursor: pointer; text-decoration: underline; margin-top: 0.5em; }"
# After a reveal on a phone, Previous and Next stand under the answer above the scene: in the
# card, below the scene and the controls, Next lay 1600 px under the answer (a teacher's
# trial). The card's pair is hidden meanwhile (one Next on screen; a second pair of buttons,
# made with the step's widgets, costs a page opened without the lesson nothing).
ANSWERED_ON_A_PHONE = (
    "@media (max-width: 767px) { :host(.twoball-answered) { display: none !important; } }"
)
# Reveal's label: while it waits for a prediction (disabled), it says what it waits for (a
# greyed "Reveal the answer" left a student pressing it, not knowing why nothing happened)
REVEAL = "Reveal the answer"
# run in the browser at a click (app/static/lesson.js): the page scrolled to the new step's
# title, or to the buttons after an answer
SHOW_STEP = "twoballShowStep();"
SHOW_ANSWER = "twoballShowAnswer();"
CHOOSE_FIRST = "Choose an answer first"
ROOM_PREDICTS = "The room predicts aloud: Reveal needs no choice."
ROOM_PREDICTS_STYLES = {"font-size": "20px", "font-style": "italic", "color": "#495057"}


class Lesson(Built):
    """The lesson's card: the step's text, its question, reveal, previous and next."""

    state = param.ClassSelector(class_=ExplorerState)

    def __init__(self, **params):
        super().__init__(**params)
        projected = self.state.presentation
        # the new step's title, which the page shows after Next (lesson.js): the card's on a
        # projector, else the question's in the main area (on a phone, above the card)
        self.heading = pn.pane.Markdown(
            sizing_mode="stretch_width",
            margin=(0, 10),
            css_classes=["twoball-step-title"] if projected else [],
            # (on a projector a paragraph's 20 px margins took the sidebar past 720 px)
            stylesheets=[TIGHT] if projected else [],
        )
        self.start = ScriptedButton(
            label="Start the lesson",
            color="primary",
            script=SHOW_STEP,  # (lesson.js)
        )
        self.start.on_click(lambda _: later(self._begin))
        # The step's widgets are made, and join the page, when the lesson starts: a page
        # opened without it (most of a class's) pays neither for their Bokeh models nor for
        # the widgets themselves (8 ms of a page's opening; docs/performance.md)
        self._steps = pn.Column(sizing_mode="stretch_width")  # in the card
        self._stage = pn.Column(sizing_mode="stretch_width")  # in the main area
        self._asking: pn.Column | None = None  # (the question, once made: _make_step_widgets)
        self._before: dict = {}  # the state when the lesson began (_begin)
        self._show()

    def _make_step_widgets(self) -> None:
        """The step's widgets (its question, choices, answer and buttons), made and placed
        when the lesson first shows a step."""
        projected = self.state.presentation
        self.choices = pn.widgets.RadioBoxGroup(
            options=[],
            value=None,
            sizing_mode="stretch_width",
            stylesheets=[":host label { white-space: normal; }"],  # long answers wrap, not cut
        )
        self.reveal = ScriptedButton(label=REVEAL, color="primary", script=SHOW_ANSWER)
        # (the page scrolls to it after a reveal: lesson.js)
        self.answer = alert(
            "",
            visible=False,
            sizing_mode="stretch_width",
            css_classes=["twoball-answer"],
            styles=PROJECTED_ANSWER if projected else {},
        )
        if projected:
            self.answer.stylesheets = [*self.answer.stylesheets, FOLD_CSS]
        # ... and on a phone, above the scene (made with the step's widgets)
        self.answer_above: pn.pane.Alert | None = None
        self.previous, self.next = self._step_buttons()
        # ... and on a phone, under the answer above the scene (:meth:`_place_answer_by_width`)
        self.phone_buttons: pn.Row | None = None
        # a step changes the drop, and with it the scenes' Bokeh models: on the next tick,
        # as every change made from the browser (see scene.later)
        self.reveal.on_click(lambda _: later(self._reveal))
        self.choices.param.watch(self._chosen, "value")
        # the question and its choices fill the main area while the class predicts
        # (:meth:`stage`; in the 300 px sidebar, beside an empty main area, they were small);
        # on a projector the reveal puts a large one-line answer above the scene
        # what to look for (with, but on a projector, the step's title), then the question
        self.look_for = pn.pane.Markdown(
            sizing_mode="stretch_width",
            styles=PROJECTED_LOOK_FOR if projected else ASKED,
            css_classes=[] if projected else ["twoball-step-title"],
            margin=(5, 10, 0, 10),
            stylesheets=[":host p:last-child { margin-bottom: 0; }"],  # close to its question
        )
        self.question = pn.pane.Markdown(
            sizing_mode="stretch_width",
            styles=PROJECTED if projected else ASKED,
            margin=(0, 10, 5, 10),
            stylesheets=[":host p { margin-top: 0.6em; }"],
        )
        self.answer_line = pn.pane.Markdown(
            visible=False,
            sizing_mode="stretch_width",
            styles=PROJECTED,
            stylesheets=[TIGHT],
        )
        # the step's aside (steps.Step.aside), under it, on every screen: what the scene shows
        # beyond the question, where the class looks (on a projector at the page's 20 px, close
        # to the answer: PROJECTED_ASIDE)
        self.aside = pn.pane.Markdown(
            visible=False,
            sizing_mode="stretch_width",
            styles=PROJECTED_ASIDE if projected else ASKED,
            margin=(0, 10),
            css_classes=["twoball-aside"],
            stylesheets=[TIGHT] if projected else [],
        )
        choices_css = PROJECTED_CHOICES if projected else ASKED_CHOICES
        self.choices.stylesheets = [*self.choices.stylesheets, choices_css]
        # on a projector Reveal waits for no choice (_waits_for_a_choice), and says so beside it:
        # a teacher's trial found it enabled with nothing chosen and nothing on screen saying why
        reveal = (
            pn.Row(
                self.reveal,
                pn.pane.Markdown(
                    ROOM_PREDICTS,
                    styles=ROOM_PREDICTS_STYLES,
                    margin=(11, 10, 0, 10),  # (its line's middle level with the button's)
                    stylesheets=[":host p { margin: 0; }"],
                ),
            )
            if projected
            else self.reveal
        )
        self._asking = pn.Column(
            self.look_for,
            self.question,
            self.choices,
            reveal,
            sizing_mode="stretch_width",
            visible=False,
        )
        self._add_step_widgets()

    def _step_buttons(self) -> tuple[pn.widgets.Button, pn.widgets.Button]:
        """Previous and Next, which go to their step (the page then shows its title:
        app/static/lesson.js)."""
        previous = ScriptedButton(label="< Previous", width=110, script=SHOW_STEP)
        following = ScriptedButton(label="Next >", color="primary", width=110, script=SHOW_STEP)
        previous.on_click(lambda _: later(lambda: self._go(self.state.step - 1)))
        following.on_click(
            lambda _: later(lambda: self._go((self.state.step + 1) % (len(STEPS) + 1)))
        )
        return previous, following

    def _begin(self) -> None:
        """The lesson's first step, in metres and seconds: a class thinks in them (the
        dimensionless view stays one click away, in the controls). What was on screen before
        is kept, to come back to at the lesson's end."""
        self._before = {name: getattr(self.state, name) for name in BEFORE_THE_LESSON}
        self.state.units = "SI"
        self._go(1)

    def _go(self, step: int) -> None:
        """Go to ``step`` (1..len(STEPS)), setting its drop and scene; 0 leaves the lesson,
        back to the drop, scene and units on screen when it began (a teacher's own set-up was
        replaced by the last step's), if it began on this page."""
        step = min(max(step, 0), len(STEPS))
        if step:
            shown = STEPS[step - 1]
            self.state.param.update(**shown.drop, scene=shown.scene, step=step, revealed=False)
        else:
            self.state.param.update(**self._before, step=0, revealed=False)
            self._before = {}

    def _chosen(self, event: param.parameterized.Event) -> None:
        self._offer_reveal()

    def _offer_reveal(self) -> None:
        """Reveal enabled once it can be pressed; while it waits for a choice, saying so."""
        waiting = self._waits_for_a_choice()
        self.reveal.param.update(
            disabled=waiting or self.answer.visible, label=CHOOSE_FIRST if waiting else REVEAL
        )

    def _waits_for_a_choice(self) -> bool:
        """A student alone predicts first (the answer waits for a choice); in front of a class
        (presentation mode) the prediction is the room's, said aloud, and the teacher reveals
        when ready (a clicker's key does)."""
        return not self.state.presentation and self.choices.value is None

    def _reveal(self) -> None:
        shown = STEPS[self.state.step - 1]
        correct = shown.choices[shown.answer]
        # the answer's numbers are the step's drop's: a slider moved while the question
        # covered the scene is moved back (a teacher's trial: the answer read "rises to
        # 8.8 m" over a plot of eps 0.67, whose h1 was 3.1 m)
        moved = {name: value for name, value in shown.drop.items()
                 if getattr(self.state, name) != value}  # fmt: skip
        if moved:
            self.state.param.update(**moved)
        # disabled before the answer shows: a clicker's next press, once the answer is on
        # screen, must find Next, not Reveal still enabled (its change sent after the answer's:
        # the press revealed again and the lesson stayed, test_a_presentation_clicker_...)
        self.reveal.disabled = True
        self.choices.disabled = True
        # the answer said once: an explanation that begins with it (with the choice's words
        # before any gloss after a colon) follows the verdict alone, and reads on from it
        # ("The answer: 4 times. 4 times: the small ball is hit..." on a projector's card;
        # "Not quite: not always: its error can be... Not always: errors 10 to...", a teacher)
        explanation = shown.explanation
        said = explanation.lower().startswith(correct.split(":")[0].lower())
        if self.choices.value is None:
            verdict = "The answer is" if said else f"The answer: {correct.lower()}."
            if said:  # ("The answer is the second, about 5 times higher...")
                explanation = explanation[0].lower() + explanation[1:]
        elif self.choices.value == correct:
            verdict = "Right."
        else:
            verdict = "Not quite." if said else f"Not quite: {correct.lower()}."
        for answer in self._answers():
            answer.param.update(
                object=f"**{verdict}** {self._explained(explanation)}",
                alert_type="success" if self.choices.value == correct else "warning",
                visible=True,
            )
        self.answer_line.param.update(
            # (one line: a choice's gloss after its colon is left to the card's explanation)
            object=f"**Answer: {correct.split(':')[0]}**",
            visible=self.state.presentation,
        )
        self.aside.param.update(object=shown.aside, visible=bool(shown.aside))
        self._answered(True)
        self.state.revealed = True  # the scene comes out from under its cover

    def _explained(self, explanation: str) -> str:
        """The explanation as the card shows it: whole, or on a projector its first sentence,
        the rest folded (:data:`FULL_EXPLANATION`)."""
        first, rest = gist(explanation)
        if not self.state.presentation or not rest:
            return explanation
        return f"{first}\n\n<details><summary>{FULL_EXPLANATION}</summary>\n\n{rest}\n\n</details>"

    @param.depends("state.step", watch=True)
    def _show(self) -> None:
        step = self.state.step
        lesson_on = step > 0
        self.start.visible = not lesson_on
        if lesson_on and self._asking is None:
            self._make_step_widgets()
        if self._asking is not None:
            for widget in (self.choices, self.reveal, self.previous, self.next):
                widget.visible = lesson_on
            for shown in (*self._answers(), self.answer_line, self.aside):
                shown.visible = False
            self._answered(False)
        if not lesson_on:
            # (on a projector the teacher says it: its three lines of 20 px, with the sliders'
            # and the folds' rows, took the sidebar past a 1280x720 screen, the Stack's too)
            self.heading.object = (
                ""
                if self.state.presentation
                else "A guided path through the demonstration in six steps: predict, then see."
            )
            return
        shown = STEPS[step - 1]
        look_for = shown.look_for
        if not self.state.presentation:  # (a phone shows the main area above the card)
            look_for = f"{self._title()}\n\n{look_for}"
        self.look_for.object = look_for
        self.question.object = f"**{shown.question}**"
        self._place_title()
        self.choices.param.update(options=list(shown.choices), value=None, disabled=False)
        self._offer_reveal()
        phone = [] if self.phone_buttons is None else [self.phone_buttons.objects]
        for previous, following in [(self.previous, self.next), *phone]:
            previous.disabled = step == 1
            following.label = "Next >" if step < len(STEPS) else "End the lesson"

    def _title(self) -> str:
        step = self.state.step
        return f"**Step {step} of {len(STEPS)}: {STEPS[step - 1].title}**"

    def _place_title(self) -> None:
        """The step's title in the card, except while the question shows it (one title on
        screen at a time; a projector's question leaves it to the card)."""
        if self.state.step and self._asking is not None:
            asked = self._asking.visible and not self.state.presentation
            self.heading.object = "" if asked else self._title()

    def _add_step_widgets(self) -> None:
        # the question in the main area (the stage), the answer and the buttons in the card;
        # on a projector the buttons come first, under the step's title: the long answer in
        # the narrow sidebar had pushed Next below a 720 px screen (to y 1303 on step 1), and
        # the class reads the one-line answer in the main area, the teacher the rest
        if not self.state.presentation:  # (whose answer above the scene is one large line)
            self._place_answer_by_width()
        above = [] if self.answer_above is None else [self.answer_above]  # (a phone's)
        buttons = [] if self.phone_buttons is None else [self.phone_buttons]  # (a phone's)
        self._stage.objects = [self._asking, *above, self.answer_line, self.aside, *buttons]
        self._card_buttons = self._buttons()
        if self.state.presentation:
            self._steps.objects = [self._card_buttons, self.answer]
        else:
            self._steps.objects = [self.answer, self._card_buttons]
        if self._layout is not None:  # (the card's foot: layout)
            join(self._layout, self._steps, len(self._layout.objects))

    def _place_answer_by_width(self) -> None:
        """The answer in the card beside the scene, and on a phone above it (:data:`PHONE`)."""
        self.answer.stylesheets = [*self.answer.stylesheets, PHONE]
        self.answer_above = alert(
            "",
            visible=False,
            sizing_mode="stretch_width",
            css_classes=["twoball-answer", "twoball-answer-above"],
            margin=(5, 10),
        )
        self.answer_above.stylesheets = [*self.answer_above.stylesheets, WIDE]
        # Previous and Next under it, after a reveal (:data:`ANSWERED_ON_A_PHONE`)
        self.phone_buttons = pn.Row(
            *self._step_buttons(),
            visible=False,
            margin=(0, 5),
            stylesheets=[WIDE],
            css_classes=["twoball-step-buttons-above"],
        )

    def _answered(self, answered: bool) -> None:
        """A phone's Previous and Next under the answer once it is revealed, the card's hidden
        meanwhile (:data:`ANSWERED_ON_A_PHONE`)."""
        if self.phone_buttons is None:
            return
        self.phone_buttons.visible = answered and self.state.step > 0
        self._card_buttons.css_classes = ["twoball-step-buttons"] + (
            ["twoball-answered"] if answered else []
        )

    def _answers(self) -> list[pn.pane.Alert]:
        """The answer's alerts: the card's, and a phone's above the scene (:data:`PHONE`)."""
        return [self.answer] + ([] if self.answer_above is None else [self.answer_above])

    def _buttons(self) -> pn.Row:
        """Previous and Next, a row that the page scrolls to after a reveal (lesson.js), but on
        a projector, where it lies above the answer."""
        return pn.Row(
            self.previous,
            self.next,
            css_classes=["twoball-step-buttons"],
            stylesheets=[ANSWERED_ON_A_PHONE],
        )

    def stage(self) -> pn.Column:
        """The step's question and choices, large, for the main area (the card then keeps the
        title, the answer and the buttons), with, on a projector, the one-line answer shown on
        reveal. Empty until the lesson starts."""
        return self._stage

    def ask(self, covered: bool) -> None:
        """Show the question while the scene is covered (:meth:`stage`)."""
        if self._asking is None:
            if not covered:
                return
            self._make_step_widgets()  # (the explorer covers a step's scene before _show)
        self._asking.visible = covered
        self._place_title()

    def layout(self) -> pn.viewable.Viewable:
        # (the step's widgets join it when first made: empty, a box in every page's document)
        return pn.Card(
            self.heading,
            self.start,
            *([self._steps] if self._steps.objects else []),
            title="Lesson",
            collapsed=False,
            sizing_mode="stretch_width",
        )
