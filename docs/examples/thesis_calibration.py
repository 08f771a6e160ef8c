"""Re-derive the thesis controller set (thesis-rig-thesis-pid, crr-quadruped-thesis-pid).

Calibrates the PID gains to the closed-loop figures thesis 4.3 and 5.5.2 publish
(pneumaquad.validation.calibration) and prints each controller's gains as the parameter
files write them, with the factors found and the relative misses of the targets. About a
minute and a half on one core.

    python docs/examples/thesis_calibration.py
"""

from pneumaquad.validation.calibration import GAIN_FIELDS, calibrate_thesis_controllers


def main() -> None:
    for found in calibrate_thesis_controllers():
        table = "[controller]" if found.controller == "rig" else f"[controller.{found.controller}]"
        factors = ", ".join(f"{name} {value:.4g}" for name, value in found.factors.items())
        misses = ", ".join(f"{100 * miss:+.1f} %" for miss in found.residuals) or "-"
        print(f"{table}  # factors: {factors}; target misses: {misses}")
        for (key, unit), value in zip(GAIN_FIELDS, found.gains, strict=True):
            print(f'{key} = "{value:.4g} {unit}"')
        print()


if __name__ == "__main__":
    main()
