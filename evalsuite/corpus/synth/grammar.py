"""The synthetic speaker's language: a small grammar whose lexicon holds semantic keywords.

Sentences are one or two phrases (joined by a comma pause); each phrase is drawn from a handful of
templates whose slots are filled from word lists. Some slots are *keyword* slots that take a word of one
of the keyword classes (:data:`KEYWORD_CLASSES`), each of which triggers a semantic gesture in the motion
model. All randomness comes from the ``numpy.random.Generator`` passed in.
"""
from __future__ import annotations

import numpy as np

__all__ = ["KEYWORD_CLASSES", "keyword_class", "Sentence", "make_sentence", "choose_emphasis", "LEXICON"]

# class -> words. The motion model's semantic gesture for each class is in model.py (GESTURE_OF_CLASS).
KEYWORD_CLASSES: dict[str, tuple[str, ...]] = {
    "up": ("up", "high", "above", "higher", "top"),
    "wide": ("big", "all", "everything", "huge", "whole"),
    "self": ("i", "me", "my", "myself", "mine"),
    "point": ("you", "there", "your", "yours", "yonder"),
    "negation": ("no", "not", "never", "nothing", "nobody"),
}
_CLASS_OF = {w: c for c, words in KEYWORD_CLASSES.items() for w in words}

LEXICON: dict[str, tuple[str, ...]] = {
    "det": ("the", "a", "this", "that", "one", "some"),
    "noun": ("house", "garden", "river", "window", "market", "letter", "story", "picture", "kitchen", "table",
             "morning", "bridge", "teacher", "music", "station", "forest", "question", "answer", "city",
             "engine", "number", "paper", "winter", "island"),
    "adj": ("old", "green", "quiet", "strange", "simple", "early", "lovely", "little", "yellow", "heavy",
            "bright", "gentle"),
    "verb": ("saw", "found", "made", "heard", "kept", "moved", "opened", "painted", "visited", "remembered",
             "carried", "followed"),
    "adv": ("today", "again", "slowly", "later", "together", "often", "outside", "before", "quickly", "yesterday"),
    "subj": ("we", "they", "she", "he", "people", "everyone"),
    "prep": ("near", "behind", "under", "beside", "across", "into"),
    "link": ("and", "but", "so", "then", "because"),
}

# Phrase templates. Upper-case slots are filled from LEXICON; "K:class" is a keyword of that class;
# "K" is a keyword of a random class.
_TEMPLATES: tuple[tuple[str, ...], ...] = (
    ("subj", "verb", "det", "adj", "noun", "adv"),
    ("K:self", "verb", "det", "noun", "prep", "det", "noun"),
    ("K:point", "verb", "det", "adj", "noun"),
    ("det", "noun", "was", "K:up", "prep", "det", "noun"),
    ("subj", "verb", "K:wide", "the", "noun", "adv"),
    ("subj", "were", "K:negation", "near", "det", "adj", "noun"),
    ("det", "adj", "noun", "verb", "K", "adv"),
    ("K:negation", "subj", "verb", "det", "noun"),
    ("subj", "verb", "det", "noun", "K:up", "there"),
    ("the", "noun", "was", "K:wide", "and", "adj"),
    ("subj", "verb", "K:self", "noun", "adv"),
    ("det", "noun", "prep", "det", "adj", "noun"),
)


def keyword_class(word: str) -> str | None:
    """The keyword class of ``word`` (case-insensitive), or None for an ordinary word."""
    return _CLASS_OF.get(word.lower())


class Sentence(tuple[tuple[str, ...], ...]):
    """A sentence: a tuple of phrases, each a tuple of lower-case words."""

    @property
    def text(self) -> str:
        return ", ".join(" ".join(p) for p in self)

    @property
    def words(self) -> list[str]:
        return [w for p in self for w in p]


def _phrase(rng: np.random.Generator) -> tuple[str, ...]:
    template = _TEMPLATES[int(rng.integers(len(_TEMPLATES)))]
    classes = sorted(KEYWORD_CLASSES)
    out: list[str] = []
    for slot in template:
        if slot.startswith("K"):
            cls = slot[2:] if ":" in slot else classes[int(rng.integers(len(classes)))]
            words = KEYWORD_CLASSES[cls]
        elif slot in LEXICON:
            words = LEXICON[slot]
        else:
            out.append(slot)
            continue
        out.append(words[int(rng.integers(len(words)))])
    return tuple(out)


def make_sentence(rng: np.random.Generator, two_phrase_p: float = 0.45) -> Sentence:
    """One sentence of one phrase, or two joined by a linking word after a comma pause."""
    first = _phrase(rng)
    if rng.random() < two_phrase_p:
        link = LEXICON["link"][int(rng.integers(len(LEXICON["link"])))]
        return Sentence((first, (link,) + _phrase(rng)))
    return Sentence((first,))


def choose_emphasis(words: list[str], rng: np.random.Generator, rate: float = 0.25,
                    keyword_weight: float = 3.0) -> list[bool]:
    """Which words are emphasised: about ``rate`` of a sentence's words (at least one), keywords and content
    words ``keyword_weight`` times as likely as function words (det, link, prep, short words)."""
    function = set(LEXICON["det"]) | set(LEXICON["link"]) | set(LEXICON["prep"]) | {"the", "was", "were", "and"}
    weight = np.array([keyword_weight if keyword_class(w) else (0.3 if w in function else 1.0) for w in words])
    n = max(1, int(round(rate * len(words) + rng.uniform(-0.5, 0.5))))
    chosen = rng.choice(len(words), size=min(n, len(words)), replace=False, p=weight / weight.sum())
    flags = [False] * len(words)
    for i in chosen:
        flags[int(i)] = True
    return flags
