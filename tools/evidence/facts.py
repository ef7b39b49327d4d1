"""The numbers and tables docs/RESULTS.md quotes, each computed from the data files the
evidence wrote (never typed by hand): results_doc.py puts them into the template, and the
suite checks that RESULTS.md is the template rendered from docs/results/.

Each fact is a function of the loaded data ({section: its JSON}) returning text; each
section's facts are in its own module, named by the section's prefix ("maps.", "rate.", ...),
and fact_text.py writes the units.
"""

import effort_facts
import firmware_facts
import maps_facts
import rate_facts
import scene_facts
import timing_facts
import zwidth_facts

FACTS = {**maps_facts.FACTS, **rate_facts.FACTS, **zwidth_facts.FACTS, **scene_facts.FACTS,
         **effort_facts.FACTS, **firmware_facts.FACTS, **timing_facts.FACTS}
