"""The settings' groups (settings_meta.GROUPS): what a plotter user means by each setting;
the ones a pen plotter does not use (spindle, probe, laser, Z) are "other", hidden by the
page unless asked."""

from __future__ import annotations

from plotbridge import settings_meta


def test_every_known_setting_has_one_group_and_other_is_what_a_plotter_does_not_use():
    grouped = [n for numbers in settings_meta.GROUPS.values() for n in numbers]
    assert len(grouped) == len(set(grouped))  # one group each
    other = sorted(n for n in settings_meta.SETTINGS if settings_meta.group(n) == "other")
    assert other == [6, 30, 31, 32, 102, 112, 122, 132]  # probe, spindle, laser, Z
    assert settings_meta.group(60) == "pen" and settings_meta.group(130) == "area"
    assert settings_meta.group(22) == "switches" and settings_meta.group(110) == "motion"
    assert settings_meta.group(999) == "other"  # a number the board has and we do not know


def test_a_groups_rows_come_as_grbl_users_read_them_not_by_number():
    known = [*sorted(settings_meta.SETTINGS), 999]
    shown = sorted(known, key=settings_meta.shown_order)
    motion = [n for n in shown if settings_meta.group(n) == "motion"]
    # steps, maximum rate, acceleration: each with its axes X, Y together, then the rest
    assert motion[:6] == [100, 101, 110, 111, 120, 121]
    assert next(n for n in shown if settings_meta.group(n) == "switches") == 22  # homing on
    groups = [settings_meta.group(n) for n in shown]
    assert groups == sorted(groups, key=list(settings_meta.GROUPS).index)  # one run per group
    assert shown[-1] == 999  # unknown: last
    assert [n for n in shown if settings_meta.group(n) == "other"] == [
        6, 30, 31, 32, 102, 112, 122, 132, 999]  # Z's rows with their kind's order
