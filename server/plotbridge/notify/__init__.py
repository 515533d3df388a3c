"""Notifications: job and plotter events told to someone away from the plotter.

`Webhooks` (webhooks.py) subscribes to the event hub; `NoticeWatcher`
(notices.py) decides what is worth telling; `Delivery` (delivery.py) posts it
to one URL, in order, retried, never holding anything else back.
"""

from plotbridge.notify.webhooks import Webhooks, check_url, check_urls

__all__ = ["Webhooks", "check_url", "check_urls"]
