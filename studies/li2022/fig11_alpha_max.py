"""Li 2022 Fig. 11: ΔV per year against the yaw limit α_max (0°-90°), weak preset otherwise.

    python studies/li2022/fig11_alpha_max.py [--reps R] [--days D]
"""

from sweep_study import main, yaw_limit_figure

if __name__ == "__main__":
    main(yaw_limit_figure("max"))
