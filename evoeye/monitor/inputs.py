"""The ADS modules a FusionMonitor can read, and the paper's input ablation (no torch here)."""

MODULES = ("perception", "prediction", "planning", "control")
# The paper's input ablation (Table "monitor ablation"): modules added one at a time.
ABLATIONS = {
    "perception": ("perception",),
    "perception+prediction": ("perception", "prediction"),
    "perception+prediction+planning": ("perception", "prediction", "planning"),
    "all": MODULES,
}


def parse_modules(text: str | None) -> tuple[str, ...] | None:
    """An ABLATIONS name or a comma list of MODULES → the modules (None stays None)."""
    if text is None:
        return None
    chosen = ABLATIONS.get(text, tuple(m.strip() for m in text.split(",")))
    unknown = set(chosen) - set(MODULES)
    if unknown or not chosen:
        raise ValueError(f"modules must be one of {list(ABLATIONS)} or a comma list of "
                         f"{list(MODULES)}, got {text!r}")
    return chosen
