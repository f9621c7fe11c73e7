"""Design studies: cases of a system over its keys, and the inverse question by the budget
(:mod:`satchain.studies.design`: which values of a key meet every target)."""
