"""The held-out study's settings (:class:`StudyConfig`) and its methods: what decides the
study's numbers (:mod:`eval.study`)."""

from __future__ import annotations

from dataclasses import dataclass

from upm.transitions import KINEMATIC_METHODS, METHODS, PERFORMED_METHODS

#: Transition methods of the default study, in table order: every registered method whose
#: window is made from the postures (not ``performed``: about a minute a window).
STUDY_METHODS = KINEMATIC_METHODS
#: Transition methods of the full study (``upm eval --full``): every registered method,
#: ``performed`` on the first :attr:`StudyConfig.performed_pairs` pairs.
FULL_METHODS = tuple(METHODS)
#: The key-posture ratio (the paper's: the key posture at the window's middle).
ALPHA = 0.5


@dataclass(frozen=True)
class StudyConfig:
    """What decides the study's numbers.

    Attributes
    ----------
    data_dir : str
        The CMU clips (``clips.csv`` gives the train/test split).
    pairs : int
        Transition pairs (and real windows per window length).
    windows : tuple of int
        Window lengths L, frames at 120 fps.
    seed : int
    methods : tuple of str
    inbetween : int or None
        Windows of the in-betweening task (:mod:`eval.inbetween`): None for as many as
        pairs, 0 for none.
    performed_pairs : int
        The pairs a performed method (``performed``: the humanoid performs the window,
        about 40 s a window at the default search) is scored on: the first N; its rows of
        the other pairs are NaN, which the summaries leave out and the paired comparisons
        skip. Not in the in-betweening task.
    """

    data_dir: str
    pairs: int = 40
    windows: tuple[int, ...] = (20,)
    seed: int = 0
    methods: tuple[str, ...] = STUDY_METHODS
    inbetween: int | None = None
    performed_pairs: int = 20

    @property
    def inbetween_windows(self) -> int:
        return self.pairs if self.inbetween is None else self.inbetween

    def as_dict(self) -> dict:
        return {"pairs": self.pairs, "windows": list(self.windows), "seed": self.seed,
                "methods": list(self.methods), "alpha": ALPHA,
                "inbetween_windows": self.inbetween_windows,
                "performed_pairs": self.performed_pairs}

    @property
    def kinematic_methods(self) -> tuple[str, ...]:
        """The methods whose windows are made from the postures alone."""
        return tuple(m for m in self.methods if m not in PERFORMED_METHODS)

    def scores(self, method: str, pair_index: int) -> bool:
        """Whether ``method`` is scored on the pair of id ``pair_index``."""
        return method not in PERFORMED_METHODS or pair_index < self.performed_pairs
