"""Configuration: the imaging system (:mod:`~satchain.config.system`, its sections in
:mod:`~satchain.config.sections` and :mod:`~satchain.config.sections_motion`), a run's configuration
(:mod:`~satchain.config.run`) and their JSON Schemas (:mod:`~satchain.config.schema`), all pydantic models read
from TOML."""
