// handshare web console: the live state document over the console's WebSocket, shared by the
// operator's page and the questionnaire. connectState(onState) calls onState with each state
// document, shows the link's state in the element with id "link", and reconnects every 2 s
// after the link is lost.
"use strict";

function connectState(onState) {
  const link = document.getElementById("link");
  const scheme = location.protocol === "https:" ? "wss://" : "ws://";
  const socket = new WebSocket(scheme + location.host + "/ws");
  socket.onopen = () => { link.textContent = "live"; link.className = "up"; };
  socket.onmessage = (event) => {
    try {
      const state = JSON.parse(event.data);
      if (state.type === "state") onState(state);
    } catch (e) {
      link.textContent = "bad state: " + e;
    }
  };
  socket.onclose = () => {
    link.textContent = "disconnected, reconnecting";
    link.className = "down";
    setTimeout(() => connectState(onState), 2000);
  };
  return socket;
}
