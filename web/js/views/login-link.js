// The one-time login link (`plotbridge users add`): /login.html#CODE. The code is used only
// when the person presses the button (a chat app previewing the link uses nothing), and
// leaves the address bar at once; the server turns it into a session cookie.
import { api } from "../api.js";
import { $, setText } from "../dom.js";

const code = location.hash.slice(1);
history.replaceState(null, "", location.pathname);
const button = $("#link-login");
if (!code) setText($("#link-error"), "This link has no login code: ask for a new link.");
else button.disabled = false;
button.addEventListener("click", async () => {
  button.disabled = true;
  try {
    await api.post("/api/login", { link: code });
    location.replace("/");
  } catch (err) {
    setText($("#link-error"), err.status === 401
      ? "This link is used up or expired: ask for a new one."
      : err.message);
  }
});
