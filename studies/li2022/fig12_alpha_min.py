"""Li 2022 Fig. 12: ΔV per year against the yaw limit α_min (0°-90°), weak preset otherwise.

    python studies/li2022/fig12_alpha_min.py [--reps R] [--days D]
"""

from sweep_study import main, yaw_limit_figure

if __name__ == "__main__":
    main(yaw_limit_figure("min"))
