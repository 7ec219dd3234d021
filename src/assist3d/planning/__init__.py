"""Relation planning: what goes where, before any position is searched. :mod:`.relations` holds the
contracts (``PlanRequest`` -> ``GroupPlan``), the relation vocabulary and ``review_plan``, the one
plan sanitiser every plan passes through; :mod:`.rules` the offline rule planner; :mod:`.planners`
the planner registry (``PLANNERS``) that the LLM planner (:mod:`.llm_planner`, with its prompts
:mod:`.llm_prompts` and answer schema :mod:`.llm_schema`, built on the client of :mod:`assist3d.llm`)
plugs into."""
