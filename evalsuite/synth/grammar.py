"""The synthetic speaker's language: a small grammar whose lexicon holds semantic keywords.

Sentences are one or two phrases (joined by a comma pause and a linking word). A phrase holds a keyword
with probability ``KEYWORD_P`` (its class drawn uniformly from :data:`KEYWORD_CLASSES`; each class triggers
a semantic gesture in the motion model); its template is drawn from that class's templates and the other
slots are filled from word lists (:data:`LEXICON`). All randomness comes from the ``numpy.random.Generator`` passed in.
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

# Phrase templates by the keyword class they hold ("" = none). Lower-case slots are filled from LEXICON;
# "K" is a keyword of the template's class; other words are literal.
_TEMPLATES: dict[str, tuple[tuple[str, ...], ...]] = {
    "up": (("det", "noun", "was", "K", "prep", "det", "noun"), ("subj", "verb", "det", "noun", "K", "again"),
           ("det", "adj", "noun", "went", "K", "adv")),
    "wide": (("subj", "verb", "K", "the", "noun", "adv"), ("the", "noun", "was", "K", "and", "adj"),
             ("subj", "saw", "a", "K", "noun", "prep", "det", "noun")),
    "self": (("K", "verb", "det", "noun", "prep", "det", "noun"), ("subj", "verb", "K", "noun", "adv"),
             ("det", "adj", "noun", "was", "K", "adv")),
    "point": (("K", "verb", "det", "adj", "noun"), ("subj", "verb", "det", "noun", "over", "K"),
              ("det", "noun", "near", "K", "was", "adj")),
    "negation": (("subj", "were", "K", "near", "det", "adj", "noun"), ("K", "subj", "verb", "det", "noun"),
                 ("det", "noun", "was", "K", "adj", "adv")),
    "": (("subj", "verb", "det", "adj", "noun", "adv"), ("det", "noun", "prep", "det", "adj", "noun")),
}
KEYWORD_P = 0.6   # a phrase holds a keyword (of a uniformly drawn class) with this probability


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
    classes = sorted(KEYWORD_CLASSES)
    cls = classes[int(rng.integers(len(classes)))] if rng.random() < KEYWORD_P else ""
    options = _TEMPLATES[cls]
    template = options[int(rng.integers(len(options)))]
    out: list[str] = []
    for slot in template:
        words = KEYWORD_CLASSES[cls] if slot == "K" else LEXICON.get(slot)
        out.append(slot if words is None else words[int(rng.integers(len(words)))])
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
