"""The paper's experiments, reproduced on mmusv output (wave study, Table I; more to come)."""
